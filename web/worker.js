// The tracker runs here, off the page's main thread: decoding (PNG, JPEG,
// .zip) and tracking both happen in WebAssembly. Requests and replies are
// those of protocol.js.
import init, {
  WasmTracker, decodeFrame, Archive, Recording, readSequenceInfo, defaultParams, parseParams, depthRgba,
} from './pkg/upetrack_wasm.js';
import { Request } from './protocol.js';

const ready = init();
let tracker = null;
let second = null;          // the tracker of the compared algorithm, if any
let secondAlgorithm = null;
let archive = null;
let recording = null;

// Parameters checked by the core, as the command checks a --params file.
const checked = (params) => parseParams(JSON.stringify(params));

// One tracker's result on a decoded frame, with its error against the truth.
function track(t, f, m) {
  const r = t.trackDecoded(f, m.depthScale, new Float64Array(m.occlusions));
  const out = {
    nodes: Array.from(r.nodes), nodesPx: Array.from(r.nodesPx), visible: Array.from(r.visible),
    status: r.status, reason: r.reason ?? null, trackMs: r.track_ms, totalMs: r.total_ms,
    cloudPoints: r.cloud_points,
  };
  r.free();
  out.error = m.groundtruth ? Array.from(t.lastError(new Float64Array(m.groundtruth))) : [];
  return out;
}

// Frame m.index decoded: from a recording, or from its two image files.
function decode(m) {
  if (m.fromRecording) {
    if (!recording) throw new Error('no recording is open');
    return recording.frame(m.index);
  }
  let color = m.color, depth = m.depth;
  if (archive && m.fromZip) {
    color = archive.read(m.colorName).buffer;
    depth = archive.read(m.depthName).buffer;
  }
  return decodeFrame(new Uint8Array(color), m.colorName, new Uint8Array(depth), m.depthName);
}

function frame(m) {
  const t0 = performance.now();
  const f = decode(m);
  const decodeMs = performance.now() - t0;
  const rgba = f.rgba;
  const out = { index: m.index, width: f.width, height: f.height, decodeMs, rgba: rgba.buffer };
  const transfer = [rgba.buffer];
  try {
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
      const d = depthRgba(f.depth);
      out.depth = d.buffer;
      transfer.push(d.buffer);
    }
  } finally {
    f.free();
  }
  return [out, transfer];
}

const handlers = {
  defaults: () => ({ params: defaultParams() }),
  zip: (m) => {
    archive = new Archive(new Uint8Array(m.bytes), m.name);
    return { names: archive.names() };
  },
  zipRead: (m) => ({ bytes: archive.read(m.path).buffer }),
  recording: (m) => {
    if (recording) recording.free();
    recording = null;
    const report = (offset, length) => postMessage({ id: m.id, progress: [offset, length] });
    recording = new Recording(m.file, m.name, m.dlo, report);
    return { info: recording.info(), details: recording.details() };
  },
  info: (m) => {
    const json = {};
    for (const [k, v] of Object.entries(m.json)) json[k] = new Uint8Array(v);
    return { info: readSequenceInfo(m.name, json, m.images) };
  },
  open: (m) => {
    if (tracker) tracker.free();
    if (second) second.free();
    const params = checked(m.params);
    tracker = new WasmTracker({ camera: m.camera, params, hsv: m.hsv });
    secondAlgorithm = m.compare || null;
    second = secondAlgorithm
      ? new WasmTracker({ camera: m.camera, params: { ...params, algorithm: secondAlgorithm }, hsv: m.hsv })
      : null;
    return {};
  },
  params: (m) => {
    const params = checked(m.params);
    if (tracker) tracker.setParams(params);
    if (second) second.setParams({ ...params, algorithm: secondAlgorithm });
    return { params };
  },
  hsv: (m) => {
    for (const t of [tracker, second]) if (t) t.setHsv(m.hsv);
    return {};
  },
  restore: (m) => {
    tracker.restore(m.snapshot ? m.snapshot.main : null);
    if (second) second.restore(m.snapshot ? m.snapshot.second : null);
    return {};
  },
  frame,
};

onmessage = async (e) => {
  const m = e.data;
  try {
    await ready;
    if (!(m.type in Request) || !(m.type in handlers)) throw new Error(`unknown request ${m.type}`);
    const r = handlers[m.type](m);
    if (Array.isArray(r)) postMessage({ id: m.id, ok: true, ...r[0] }, r[1]);
    else postMessage({ id: m.id, ok: true, ...(r ?? {}) });
  } catch (err) {
    postMessage({ id: m.id, ok: false, error: String(err && err.message ? err.message : err) });
  }
};
