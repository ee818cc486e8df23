// The tracker runs here, off the page's main thread. A frame's colour file
// is decoded by the browser's own decoder (createImageBitmap, which works
// off this thread) as soon as its request arrives, while earlier frames are
// still being tracked; depth PNGs, .zip, recordings and tracking run in
// WebAssembly, in the order the requests came. `decoder: 'wasm'` decodes
// colour in WebAssembly too, bit for bit as the command does; `canvas`
// always takes the createImageBitmap route. Requests and
// replies are those of protocol.js.
import init, {
  WasmTracker, decodeFrame, decodeBitmapFrame, decodeRgbaFrame, colourOnlyFrame, Archive, Recording, readSequenceInfo, defaultParams, parseParams, depthRgba,
} from './pkg/upetrack_wasm.js';
import { Request } from './protocol.js';

const ready = init();
let tracker = null;
let second = null;          // the tracker of the compared algorithm, if any
let secondAlgorithm = null;
let archive = null;
let recording = null;
let opened = null;          // { camera, hsv, rope, hint } of the trackers, for the explain mode's own tracker

// Parameters checked by the core, as the command checks a --params file.
const checked = (params) => parseParams(JSON.stringify(params));

// One tracker's result on a decoded frame, with its error against the truth.
function track(t, f, m) {
  const r = t.trackDecoded(f, m.depthScale, new Float64Array(m.occlusions));
  const out = {
    nodes: Array.from(r.nodes), nodesPx: Array.from(r.nodesPx), visible: Array.from(r.visible),
    status: r.status, reason: r.reason ?? null, init: r.init, segmentMs: r.segment_ms, cloudMs: r.cloud_ms, trackMs: r.track_ms, totalMs: r.total_ms,
    cloudPoints: r.cloud_points, record: r.record,
  };
  const ropes = r.ropes;
  r.free();
  out.error = m.groundtruth ? Array.from(t.lastError(new Float64Array(m.groundtruth))) : [];
  // Several ropes: each one's nodes and error against its own truth.
  out.ropes = ropes.map((x, k) => {
    const truth = m.ropeTruths[k];
    return {
      name: x.name, nodes: x.nodes, nodesPx: x.nodes_px, visible: x.visible.map((v) => (v ? 1 : 0)),
      status: x.status, reason: x.reason ?? null, record: x.record,
      error: truth ? Array.from(t.lastErrorOf(k, new Float64Array(truth))) : [],
    };
  });
  return out;
}

// A tracker of the opened sequence (its ropes, if several, each with the
// pixel clicked on it, if any).
function makeTracker(o, params) {
  const ropes = o.ropes.length ? o.ropes.map(({ name, hsv, rope }) => ({ name, hsv, rope })) : null;
  const t = new WasmTracker({ camera: o.camera, fps: o.fps, params, hsv: o.hsv, rope: o.rope, ropes });
  if (!ropes && o.hint) t.setRopeHint(o.hint[0], o.hint[1]);
  o.ropes.forEach((r, k) => { if (r.hint) t.setRopeHintOf(k, r.hint[0], r.hint[1]); });
  return t;
}

// What the browser's decoders must leave alone for the pixels to be the file's.
const AS_STORED = { colorSpaceConversion: 'none', premultiplyAlpha: 'none' };
const IMAGE_TYPES = { jpg: 'image/jpeg', jpeg: 'image/jpeg', png: 'image/png' };

// The browser's decoding of a colour file, started at once. `canvas`
// (createImageBitmap, read back through an OffscreenCanvas in wasm) serves
// where ImageDecoder does not (or where it is asked for); ImageDecoder
// gives the RGBA pixels directly and is about twice as fast here.
// Resolves to { rgba, width, height } or { bitmap }, with the ms it took.
async function browserDecode(bytes, name, decoder) {
  const t0 = performance.now();
  const type = IMAGE_TYPES[name.split('.').pop().toLowerCase()];
  if (decoder === 'browser' && self.ImageDecoder && type) {
    const d = new ImageDecoder({ data: bytes, type, ...AS_STORED });
    try {
      const { image } = await d.decode();
      try {
        const width = image.displayWidth, height = image.displayHeight;
        const options = { rect: { x: 0, y: 0, width, height }, format: 'RGBA', layout: [{ offset: 0, stride: 4 * width }] };
        const rgba = new Uint8Array(image.allocationSize(options));
        await image.copyTo(rgba, options);
        return { rgba, width, height, ms: performance.now() - t0 };
      } finally {
        image.close();
      }
    } finally {
      d.close();
    }
  }
  const bitmap = await createImageBitmap(new Blob([bytes]), AS_STORED);
  return { bitmap, ms: performance.now() - t0 };
}

const BROWSER_DECODERS = new Set(['browser', 'canvas']);

// Colour decoding started when a frame's request arrives (its files came
// with it), before the frames ahead of it are tracked.
function startDecode(m) {
  if (!BROWSER_DECODERS.has(m.decoder) || m.fromRecording || m.fromZip || !m.color) return null;
  const p = browserDecode(m.color, m.colorName, m.decoder);
  p.catch(() => {});
  return p;
}

// A webcam's frame (an ImageBitmap, transferred), read back through an
// OffscreenCanvas; its depth is constant (colourOnlyFrame).
function colourOnly(bitmap) {
  const t0 = performance.now();
  try {
    return [colourOnlyFrame(bitmap), performance.now() - t0];
  } finally {
    bitmap.close();
  }
}

// Frame m.index decoded, and the milliseconds its decoding took.
async function decode(m, early) {
  if (m.fromRecording) {
    if (!recording) throw new Error('no recording is open');
    const t0 = performance.now();
    const f = recording.frame(m.index);
    return [f, performance.now() - t0];
  }
  let color = m.color, depth = m.depth;
  if (archive && m.fromZip) {
    color = archive.read(m.colorName).buffer;
    depth = archive.read(m.depthName).buffer;
  }
  const colorDecode = early || (BROWSER_DECODERS.has(m.decoder) ? browserDecode(color, m.colorName, m.decoder) : null);
  if (!colorDecode) {
    const t0 = performance.now();
    const f = decodeFrame(new Uint8Array(color), m.colorName, new Uint8Array(depth), m.depthName);
    return [f, performance.now() - t0];
  }
  let c;
  try {
    c = await colorDecode;
  } catch (err) {
    throw new Error(`${m.colorName}: the browser cannot decode this image (${err.message || err})`);
  }
  const t0 = performance.now();
  const d = new Uint8Array(depth);
  if (c.rgba) return [decodeRgbaFrame(c.rgba, c.width, c.height, m.colorName, d, m.depthName), c.ms + performance.now() - t0];
  try {
    return [decodeBitmapFrame(c.bitmap, m.colorName, d, m.depthName), c.ms + performance.now() - t0];
  } finally {
    c.bitmap.close();
  }
}

async function frame(m, early) {
  const [f, decodeMs] = m.bitmap ? colourOnly(m.bitmap) : await decode(m, early);
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
    const ropes = (m.ropes || []).map((r) => ({ name: r.name, hsv: r.hsv, rope: r.rope, hint: r.hint || null }));
    opened = { camera: m.camera, fps: m.fps, hsv: m.hsv, rope: m.rope || null, hint: null, ropes };
    tracker = makeTracker(opened, params);
    secondAlgorithm = m.compare || null;
    second = secondAlgorithm ? makeTracker(opened, { ...params, algorithm: secondAlgorithm }) : null;
    return {};
  },
  // One more rope, of the colour `hsv`, through the pixel `hint`: every
  // tracker is made again with it (the ropes are found again from the
  // shown frame on).
  addRope: (m) => {
    if (!opened) throw new Error('no sequence is open');
    if (!opened.ropes.length) opened.ropes = [{ name: 'rope-0', hsv: opened.hsv, rope: opened.rope, hint: opened.hint }];
    if (opened.ropes.length >= 8) throw new Error('8 ropes at most are tracked at once');
    opened.ropes.push({ name: `rope-${opened.ropes.length}`, hsv: m.hsv, rope: null, hint: m.hint });
    const params = tracker.params();
    tracker.free();
    tracker = makeTracker(opened, params);
    if (second) {
      second.free();
      second = makeTracker(opened, { ...params, algorithm: secondAlgorithm });
    }
    return { ropes: opened.ropes.map(({ name, hsv, rope, hint }) => ({ name, hsv, rope, hint })) };
  },
  rope: (m) => {
    for (const t of [tracker, second]) {
      if (!t) continue;
      t.setRopePrior(m.prior);
      if (m.hint) t.setRopeHint(m.hint[0], m.hint[1]);
    }
    if (opened) Object.assign(opened, { rope: m.prior, hint: m.hint || opened.hint });
    if (opened && opened.ropes.length) Object.assign(opened.ropes[0], { rope: m.prior, hint: m.hint || opened.ropes[0].hint });
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
    if (opened) opened.hsv = m.hsv;
    return {};
  },
  // One frame explained from the state after the frame before it (its
  // snapshot), by a tracker of its own: the main one is not touched.
  explain: async (m, early) => {
    if (!opened) throw new Error('no sequence is open');
    const [f] = await decode(m, early);
    const t = makeTracker(opened, tracker.params());
    try {
      t.restore(m.snapshot);
      const view = t.explainRope(m.rope || 0, f, m.depthScale, new Float64Array(m.occlusions));
      const mask = t.lastMask();
      const rgba = f.rgba;
      return [{ view, rgba: rgba.buffer, mask: mask.buffer, width: f.width, height: f.height }, [rgba.buffer, mask.buffer]];
    } finally {
      t.free();
      f.free();
    }
  },
  restore: (m) => {
    tracker.restore(m.snapshot ? m.snapshot.main : null);
    if (second) second.restore(m.snapshot ? m.snapshot.second : null);
    return {};
  },
  frame,
};

// Requests are served one at a time in arrival order; only a frame's
// browser decoding starts on arrival.
let queue = Promise.resolve();
onmessage = (e) => {
  const m = e.data;
  const early = m.type === 'frame' || m.type === 'explain' ? startDecode(m) : null;
  queue = queue.then(() => serve(m, early));
};

async function serve(m, early) {
  try {
    await ready;
    if (!(m.type in Request) || !(m.type in handlers)) throw new Error(`unknown request ${m.type}`);
    const r = await handlers[m.type](m, early);
    if (Array.isArray(r)) postMessage({ id: m.id, ok: true, ...r[0] }, r[1]);
    else postMessage({ id: m.id, ok: true, ...(r ?? {}) });
  } catch (err) {
    postMessage({ id: m.id, ok: false, error: String(err && err.message ? err.message : err) });
  }
};
