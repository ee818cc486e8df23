// The tracker runs here, off the page's main thread: decoding (PNG, JPEG,
// .zip) and tracking both happen in WebAssembly.
import init, { WasmTracker, decodeFrame, Archive, readSequenceInfo, defaultParams } from './pkg/upetrack_wasm.js';

const ready = init();
let tracker = null;
let second = null;          // the tracker of the compared algorithm, if any
let secondAlgorithm = null;
let archive = null;

// One tracker's result on a decoded frame, with its error against the truth.
function track(t, f, m) {
  const r = t.trackDecoded(f, m.depthScale, new Int32Array(m.occlusions));
  const out = {
    nodes: Array.from(r.nodes), nodesPx: Array.from(r.nodesPx), visible: Array.from(r.visible),
    status: r.status, reason: r.reason ?? null, trackMs: r.track_ms, totalMs: r.total_ms,
    cloudPoints: r.cloud_points,
  };
  r.free();
  out.error = m.groundtruth ? Array.from(t.lastError(new Float64Array(m.groundtruth))) : [];
  return out;
}

function reply(id, body, transfer = []) {
  postMessage({ id, ok: true, ...body }, transfer);
}

async function handle(m) {
  await ready;
  switch (m.type) {
    case 'defaults':
      return { params: defaultParams() };
    case 'zip': {
      archive = new Archive(new Uint8Array(m.bytes), m.name);
      return { names: archive.names() };
    }
    case 'zipRead':
      return { bytes: archive.read(m.path).buffer };
    case 'info': {
      const json = {};
      for (const [k, v] of Object.entries(m.json)) json[k] = new Uint8Array(v);
      return { info: readSequenceInfo(m.name, json, m.images) };
    }
    case 'open':
      if (tracker) tracker.free();
      if (second) second.free();
      tracker = new WasmTracker({ camera: m.camera, params: m.params, hsv: m.hsv });
      secondAlgorithm = m.compare || null;
      second = secondAlgorithm
        ? new WasmTracker({ camera: m.camera, params: { ...m.params, algorithm: secondAlgorithm }, hsv: m.hsv })
        : null;
      return {};
    case 'params':
      tracker.setParams(m.params);
      if (second) second.setParams({ ...m.params, algorithm: secondAlgorithm });
      return { params: tracker.params() };
    case 'hsv':
      for (const t of [tracker, second]) if (t) t.setHsv(new Uint8Array(m.lower), new Uint8Array(m.upper));
      return {};
    case 'restore':
      tracker.restore(m.snapshot ? m.snapshot.main : null);
      if (second) second.restore(m.snapshot ? m.snapshot.second : null);
      return {};
    case 'frame': {
      let color = m.color, depth = m.depth;
      if (archive && m.fromZip) {
        color = archive.read(m.colorName).buffer;
        depth = archive.read(m.depthName).buffer;
      }
      const t0 = performance.now();
      const f = decodeFrame(new Uint8Array(color), m.colorName, new Uint8Array(depth), m.depthName);
      const decodeMs = performance.now() - t0;
      const rgba = f.rgba;
      const out = { index: m.index, width: f.width, height: f.height, decodeMs, rgba: rgba.buffer };
      const transfer = [rgba.buffer];
      if (m.track) {
        Object.assign(out, track(tracker, f, m));
        if (second) out.second = track(second, f, m);
        out.snapshot = { main: tracker.snapshot(), second: second ? second.snapshot() : null };
        if (m.wantMask) {
          const mask = tracker.lastMask();
          out.mask = mask.buffer;
          transfer.push(mask.buffer);
        }
      }
      if (m.wantDepth) {
        const d = f.depth;
        out.depth = d.buffer;
        transfer.push(d.buffer);
      }
      f.free();
      return [out, transfer];
    }
    default:
      throw new Error(`unknown request ${m.type}`);
  }
}

onmessage = async (e) => {
  const m = e.data;
  try {
    const r = await handle(m);
    if (Array.isArray(r)) reply(m.id, r[0], r[1]);
    else reply(m.id, r ?? {});
  } catch (err) {
    postMessage({ id: m.id, ok: false, error: String(err && err.message ? err.message : err) });
  }
};
