// Opening sequences (bundled samples, a folder, dropped files, a .zip) and
// reading one frame's files, at most one frame ahead.
import { state, progress, $, settleLookahead } from './state.js';
import { call } from './worker-client.js';
import { Request } from './protocol.js';
import { commonRoot, activeOcclusions, inputKind, inputHeadBytes } from './core.js';

// Set by app.js: what happens once a sequence is open (show frame 0).
export const hooks = { opened: async () => {}, closing: () => {} };

async function openSequence(name, paths, read, fromZip = false) {
  const generation = ++state.generation;
  state.playing = false;
  const jsonNames = paths.filter((p) => !p.includes('/') && p.toLowerCase().endsWith('.json'));
  const json = {};
  let done = 0;
  for (const n of jsonNames) {
    json[n] = await read(n);
    progress(++done, jsonNames.length + 1);
  }
  // Every file one folder down: which folders hold the frames is the core's rule.
  const images = paths.filter((p) => /^[^/]+\/[^/]+$/.test(p));
  const { info } = await call(Request.info(name, json, images));
  await finishOpening(generation, { name, info, read, fromZip, fromRecording: false });
}

// What a file is, by its first bytes, whatever its name: a recording (ROS1
// .bag of the RealSense Viewer, rs-record up to 2.55 or realsense-ros,
// rosbag2 .db3 of librealsense 2.59 or ROS 2, .mcap), a zip, or what else
// (the core's rule, as the command's): `{kind, what}`.
export async function kindOf(file) {
  return inputKind(new Uint8Array(await file.slice(0, inputHeadBytes()).arrayBuffer()));
}

// A recording, with an optional dlo.json picked or dropped beside it. The
// worker reads the file in slices; without a dlo.json, the user picks the
// rope's colour by clicking it.
export async function openRecording(file, dloFile) {
  const generation = ++state.generation;
  state.playing = false;
  progress(0, 1);
  const dlo = dloFile ? await dloFile.text() : null;
  const { info, details } = await call(Request.recording(file, file.name, dlo));
  await finishOpening(generation, {
    name: file.name, info, details, read: null, fromZip: false, fromRecording: true, configured: !!dloFile,
  });
}

async function finishOpening(generation, seq) {
  const { info } = seq;
  hooks.closing();
  await settleLookahead();
  await call(Request.open(info.camera, info.fps, state.params, info.hsv, info.rope || null, state.compare, info.ropes || []));
  if (generation !== state.generation) return;
  state.seq = seq;
  state.rope = info.rope || null;
  state.sampleName = null;
  $('sample').selectedIndex = -1; // the sample list shows none while another sequence is open
  state.hsv = info.hsv;
  state.index = 0;
  state.tracked = -1;
  state.results = [];
  state.userRects = [];
  progress(null);
  await hooks.opened();
}

export async function loadSample(name, index) {
  const entry = index.samples.find((s) => s.name === name);
  if (!entry) throw new Error(`no sample named ${name}`);
  const base = new URL(`../samples/${encodeURIComponent(name)}/`, import.meta.url);
  const read = async (p) => {
    const r = await fetch(new URL(p, base));
    if (!r.ok) throw new Error(`samples/${name}/${p}: HTTP ${r.status}`);
    return r.arrayBuffer();
  };
  await openSequence(name, entry.files, read);
  state.sampleName = name;
  $('sample').value = name;
}

// A scene made in the tab: `files` maps each path to its bytes.
export async function openGenerated(name, files) {
  const read = async (p) => {
    if (!(p in files)) throw new Error(`${name}/${p}: missing`);
    return files[p].slice(0); // a copy: the one sent to the worker is transferred
  };
  return openSequence(name, Object.keys(files), read);
}

// Files from a folder picker or a drop ({ path, file }): the folders above
// the sequence's layout are stripped (the core's rule).
export async function openFiles(files, label) {
  // One or two files: a .zip, a recording (with its dlo.json), or a mistake named for what it is.
  if (files.length <= 2) {
    const kinds = await Promise.all(files.map((f) => kindOf(f.file)));
    if (files.length === 1 && kinds[0].kind === 'zip') return openZip(files[0].file);
    const r = kinds.findIndex((k) => k.kind === 'recording');
    if (r >= 0) {
      const other = files[1 - r];
      if (other && !/\.json$/i.test(other.path)) throw new Error(`${other.path}: open a recording alone or with its dlo.json`);
      return openRecording(files[r].file, other ? other.file : null);
    }
    if (files.length === 1 && !files[0].path.includes('/')) {
      // A loose file, not a folder of one.
      throw new Error(`${files[0].path} is ${kinds[0].what}: open a sequence folder, a .zip of one, or a recording (.bag, .db3, .mcap).`);
    }
  }
  const paths = files.map((f) => f.path.split('/').filter(Boolean).join('/'));
  const root = commonRoot(paths);
  const cut = root ? root.length + 1 : 0;
  const map = new Map();
  paths.forEach((p, i) => map.set(p.slice(cut), files[i].file));
  const name = root ? root.split('/').pop() : label;
  const read = async (p) => {
    const f = map.get(p);
    if (!f) throw new Error(`${name}/${p}: missing`);
    return f.arrayBuffer();
  };
  return openSequence(name, [...map.keys()], read);
}

function readWithProgress(file) {
  return new Promise((resolve, reject) => {
    const r = new FileReader();
    r.onprogress = (e) => progress(e.loaded, e.total || 1);
    r.onload = () => resolve(r.result);
    r.onerror = () => reject(new Error(`${file.name}: ${r.error}`));
    r.readAsArrayBuffer(file);
  });
}

export async function openZip(file) {
  const bytes = await readWithProgress(file);
  progress(0);
  const { names } = await call(Request.zip(bytes, file.name), [bytes]);
  const read = async (p) => (await call(Request.zipRead(p))).bytes;
  return openSequence(file.name, names, read, true);
}

// Every file under a dropped entry, with its path.
export async function entryFiles(entry, prefix, out) {
  if (entry.isFile) {
    const file = await new Promise((res, rej) => entry.file(res, rej));
    out.push({ path: prefix + entry.name, file });
  } else if (entry.isDirectory) {
    const reader = entry.createReader();
    for (;;) {
      const batch = await new Promise((res, rej) => reader.readEntries(res, rej));
      if (!batch.length) break;
      for (const e of batch) await entryFiles(e, `${prefix}${entry.name}/`, out);
    }
  }
}

// The occlusion rectangles of frame i: the sequence's and the drawn ones, flat.
export function activeRects(i) {
  const flat = Array.from(activeOcclusions(state.seq.info.occlusions, i));
  for (const r of state.userRects) flat.push(...r);
  return flat;
}

// File bytes of frame i, read ahead up to READ_AHEAD frames: a fetched
// sample's files take a round trip each, which one frame ahead did not hide.
const READ_AHEAD = 4;
const ahead = new Map();
function readBoth(seq, i) {
  return Promise.all([seq.read(seq.info.color_files[i]), seq.read(seq.info.depth_files[i])]);
}
function prefetch(from) {
  const seq = state.seq;
  const n = seq.info.color_files.length;
  for (const [k, hit] of ahead) if (hit.seq !== seq || k < from || k >= from + READ_AHEAD) ahead.delete(k);
  for (let i = from; i < Math.min(n, from + READ_AHEAD); i++) {
    if (ahead.has(i)) continue;
    const p = readBoth(seq, i);
    p.catch(() => {});
    ahead.set(i, { seq, p });
  }
}
function readPair(i) {
  const hit = ahead.get(i);
  ahead.delete(i);
  return hit && hit.seq === state.seq ? hit.p : readBoth(state.seq, i);
}

// The fields of a frame request for frame i, and the buffers to transfer.
export async function frameFields(i, track) {
  const seq = state.seq;
  const info = seq.info;
  let color = null;
  let depth = null;
  const transfer = [];
  if (!seq.fromZip && !seq.fromRecording) {
    [color, depth] = await readPair(i);
    transfer.push(color, depth);
    // Read the next frames' files while this one is decoded and tracked.
    prefetch(i + 1);
  }
  const fields = {
    index: i, track, color, depth, colorName: info.color_files[i], depthName: info.depth_files[i],
    fromZip: seq.fromZip, fromRecording: seq.fromRecording, depthScale: info.depth_scale, occlusions: activeRects(i),
    groundtruth: info.groundtruth[i], ropeTruths: (info.ropes || []).map((r) => r.groundtruth[i]),
    wantMask: $('show-mask').checked, wantDepth: $('show-depth').checked,
    decoder: state.decoder,
  };
  return [fields, transfer];
}

// Decodes (and, with `track`, tracks) frame i in the worker.
export async function requestFrame(i, track) {
  const [fields, transfer] = await frameFields(i, track);
  return call(Request.frame(fields), transfer);
}
