// Scenes made in the tab: the project's simulator and renderer (compiled to
// WebAssembly) run in a worker of their own, so that the tracker's worker
// keeps playing while a scene is made. Request: { options } (SynthScene's);
// replies: { progress: [written, total] } while rendering, then
// { ok: true, name, files: { path: ArrayBuffer } } or { ok: false, error }.
import init, { SynthScene } from './pkg/upetrack_wasm.js';

const ready = init();
// Frames rendered between two progress messages.
const BATCH = 5;

onmessage = async (e) => {
  const { options } = e.data;
  let scene = null;
  try {
    await ready;
    scene = new SynthScene(options);
    const total = scene.total();
    for (let done = 0; done < total;) {
      done = scene.render(BATCH);
      postMessage({ progress: [done, total] });
    }
    const files = {};
    const transfer = [];
    for (const path of scene.names()) {
      const bytes = scene.read(path);
      files[path] = bytes.buffer;
      transfer.push(bytes.buffer);
    }
    postMessage({ ok: true, name: `${options.scenario} (seed ${options.seed})`, files }, transfer);
  } catch (err) {
    postMessage({ ok: false, error: String(err && err.message ? err.message : err) });
  } finally {
    if (scene) scene.free();
  }
};
