// The demo page: loads sequences (bundled samples, a folder, a .zip), sends
// frames to the tracker in a Web Worker, and draws nodes, curve, ground
// truth, the error plot and timings. Plain ES module, no bundler.

const $ = (id) => document.getElementById(id);
const worker = new Worker('./worker.js', { type: 'module' });
const pending = new Map();
let nextId = 1;
worker.onmessage = (e) => {
  const p = pending.get(e.data.id);
  if (!p) return;
  pending.delete(e.data.id);
  if (e.data.ok) p.resolve(e.data); else p.reject(new Error(e.data.error));
};
worker.onerror = (e) => showError(`Worker failed: ${e.message}`);
function call(msg, transfer = []) {
  return new Promise((resolve, reject) => {
    const id = nextId++;
    pending.set(id, { resolve, reject });
    worker.postMessage({ ...msg, id }, transfer);
  });
}

const PARAM_FIELDS = ['node_count', 'displacement_decay', 'curvature_retention', 'bending_resistance',
  'displacement_weight', 'end_displacement_weight', 'visibility_radius', 'visibility_min_points'];
const MM_FIELDS = new Set(['visibility_radius']);
const ALGORITHM_NAMES = { upetrack: 'UPETrack', cpd: 'CPD', trackdlo: 'TrackDLO' };

const state = {
  seq: null,          // { name, info, read(path), fromZip }
  index: 0,           // frame shown
  tracked: -1,        // last frame tracked (frames are tracked in order)
  results: [],        // per frame: { nodes, nodesPx, visible, status, reason, trackMs, totalMs, error }
  params: null,       // parameters in force (all fields, with the algorithm)
  compare: '',        // algorithm tracked alongside for comparison ('' for none)
  userRects: [],      // [x, y, w, h] drawn on the image
  playing: false,
  busy: Promise.resolve(),
  frame: null,        // last decoded frame { width, height, rgba, mask, depth }
  mode: 'none',       // 'draw' | 'pick'
  shownAt: [],        // display timestamps, for the frame rate
  generation: 0,      // bumped when a new sequence opens
  epoch: 0,           // bumped when settings change; a look-ahead from an older epoch is dropped
  lookahead: null,    // { index, epoch, generation, promise } of the next frame, while playing
};

// ---------- messages and progress ----------
function showError(text) {
  $('message-text').textContent = text;
  $('message').hidden = false;
  console.warn(text);
}
$('message-close').onclick = () => { $('message').hidden = true; };
function progress(value, max) {
  const p = $('progress');
  if (value === null) { p.hidden = true; return; }
  p.hidden = false;
  if (max) { p.max = max; p.value = value; } else p.removeAttribute('value');
}

// ---------- opening sequences ----------
async function openSequence(name, paths, read, fromZip = false) {
  const generation = ++state.generation;
  state.playing = false;
  updatePlayButton();
  const jsonNames = paths.filter((p) => !p.includes('/') && p.toLowerCase().endsWith('.json'));
  const json = {};
  let done = 0;
  for (const n of jsonNames) {
    json[n] = await read(n);
    progress(++done, jsonNames.length + 1);
  }
  const images = paths.filter((p) => /^(color|rgb|image|depth)\/[^/]+$/i.test(p));
  const { info } = await call({ type: 'info', name, json, images });
  await call({ type: 'open', camera: info.camera, params: state.params, hsv: info.hsv, compare: state.compare });
  if (generation !== state.generation) return;
  state.seq = { name, info, read, fromZip };
  state.index = 0;
  state.tracked = -1;
  state.results = [];
  state.userRects = [];
  renderRects();
  setHsvInputs(info.hsv);
  $('timeline').max = String(info.color_files.length - 1);
  $('canvas').width = info.camera.width;
  $('canvas').height = info.camera.height;
  progress(null);
  await goTo(0);
}

async function loadSample(name, index) {
  const entry = index.samples.find((s) => s.name === name);
  if (!entry) throw new Error(`no sample named ${name}`);
  const base = new URL(`../samples/${encodeURIComponent(name)}/`, import.meta.url);
  const read = async (p) => {
    const r = await fetch(new URL(p, base));
    if (!r.ok) throw new Error(`samples/${name}/${p}: HTTP ${r.status}`);
    return r.arrayBuffer();
  };
  await openSequence(name, entry.files, read);
}

// Files from a folder picker or a drop: strip the folder's own name.
async function openFiles(files, label) {
  const zip = files.find((f) => f.path.toLowerCase().endsWith('.zip'));
  if (zip && files.length === 1) return openZip(zip.file);
  const map = new Map();
  const parts = files.map((f) => f.path.split('/').filter(Boolean));
  const common = parts.length && parts.every((p) => p.length > 1 && p[0] === parts[0][0]) ? 1 : 0;
  for (let i = 0; i < files.length; i++) map.set(parts[i].slice(common).join('/'), files[i].file);
  const name = common ? parts[0][0] : label;
  const read = async (p) => {
    const f = map.get(p);
    if (!f) throw new Error(`${name}/${p}: missing`);
    return f.arrayBuffer();
  };
  await openSequence(name, [...map.keys()], read);
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

async function openZip(file) {
  const bytes = await readWithProgress(file);
  progress(0);
  const { names } = await call({ type: 'zip', bytes, name: file.name }, [bytes]);
  const read = async (p) => (await call({ type: 'zipRead', path: p })).bytes;
  await openSequence(file.name, names, read, true);
}

async function entryFiles(entry, prefix, out) {
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

function guarded(fn) {
  return async (...args) => {
    try { await fn(...args); } catch (err) { progress(null); showError(err.message || String(err)); }
  };
}

$('folder').onchange = guarded(async (e) => {
  const files = [...e.target.files].map((f) => ({ path: f.webkitRelativePath || f.name, file: f }));
  e.target.value = '';
  if (!files.length) throw new Error('The folder is empty.');
  await openFiles(files, 'folder');
});
$('zip').onchange = guarded(async (e) => {
  const f = e.target.files[0];
  e.target.value = '';
  if (f) await openZip(f);
});
const stage = $('stage');
stage.ondragover = (e) => { e.preventDefault(); $('drop-hint').hidden = false; };
stage.ondragleave = () => { $('drop-hint').hidden = true; };
stage.ondrop = guarded(async (e) => {
  e.preventDefault();
  $('drop-hint').hidden = true;
  const items = [...e.dataTransfer.items].map((i) => i.webkitGetAsEntry && i.webkitGetAsEntry()).filter(Boolean);
  const files = [];
  if (items.length) for (const it of items) await entryFiles(it, '', files);
  else for (const f of e.dataTransfer.files) files.push({ path: f.name, file: f });
  if (!files.length) throw new Error('Nothing to open in what was dropped.');
  await openFiles(files, 'dropped');
});

// ---------- frames ----------
function activeRects(i) {
  const flat = [];
  for (const o of state.seq.info.occlusions) {
    if (i >= o.frames[0] && i <= o.frames[1]) flat.push(...o.rect);
  }
  for (const r of state.userRects) flat.push(...r);
  return flat;
}

// File bytes of frame i, read ahead at most one frame.
const ahead = new Map();
function prefetch(i) {
  const seq = state.seq;
  if (ahead.has(i)) return;
  ahead.clear();
  const p = Promise.all([seq.read(seq.info.color_files[i]), seq.read(seq.info.depth_files[i])]);
  p.catch(() => {});
  ahead.set(i, { seq, p });
}
function readPair(i) {
  const hit = ahead.get(i);
  ahead.delete(i);
  if (hit && hit.seq === state.seq) return hit.p;
  const seq = state.seq;
  return Promise.all([seq.read(seq.info.color_files[i]), seq.read(seq.info.depth_files[i])]);
}

async function requestFrame(i, track) {
  const seq = state.seq;
  const info = seq.info;
  const colorName = info.color_files[i];
  const depthName = info.depth_files[i];
  let color = null;
  let depth = null;
  const transfer = [];
  if (!seq.fromZip) {
    [color, depth] = await readPair(i);
    transfer.push(color, depth);
    // Read the next frame's files while this one is decoded and tracked.
    if (i + 1 < info.color_files.length) prefetch(i + 1);
  }
  const gt = info.groundtruth[i];
  return call({
    type: 'frame', index: i, track, color, depth, colorName, depthName, fromZip: seq.fromZip,
    depthScale: info.depth_scale, occlusions: activeRects(i), groundtruth: gt,
    wantMask: $('show-mask').checked, wantDepth: $('show-depth').checked,
  }, transfer);
}

// Shows frame i, tracking every frame up to it first (tracking is sequential).
function goTo(i) {
  state.busy = state.busy.then(() => goToNow(i)).catch((err) => {
    state.playing = false;
    updatePlayButton();
    showError(err.message || String(err));
  });
  return state.busy;
}

async function goToNow(i) {
  if (!state.seq) return;
  const n = state.seq.info.color_files.length;
  i = Math.max(0, Math.min(n - 1, i));
  const generation = state.generation;
  let r = null;
  if (i <= state.tracked) {
    r = await requestFrame(i, false);
  } else {
    const from = state.tracked + 1;
    for (let k = from; k <= i; k++) {
      const look = state.lookahead;
      state.lookahead = null;
      const usable = look && look.index === k && look.epoch === state.epoch && look.generation === generation;
      r = await (usable ? look.promise : requestFrame(k, true));
      if (generation !== state.generation) return;
      state.results[k] = {
        nodes: r.nodes, nodesPx: r.nodesPx, visible: r.visible, status: r.status, reason: r.reason,
        trackMs: r.trackMs, totalMs: r.totalMs, decodeMs: r.decodeMs, error: r.error, snapshot: r.snapshot,
        second: r.second || null,
      };
      state.tracked = k;
      // While playing, the next frame is requested before this one is drawn,
      // so that the worker decodes and tracks while the page draws.
      if (state.playing && k === i && k + 1 < n) {
        const promise = requestFrame(k + 1, true);
        promise.catch(() => {});
        state.lookahead = { index: k + 1, epoch: state.epoch, generation, promise };
      }
      if (k < i && (k - from) % 10 === 9) progress(k - from, i - from);
    }
    progress(null);
  }
  if (generation !== state.generation) return;
  state.index = i;
  state.frame = { width: r.width, height: r.height, rgba: new Uint8ClampedArray(r.rgba), mask: r.mask ? new Uint8Array(r.mask) : null, depth: r.depth ? new Uint16Array(r.depth) : null, decodeMs: r.decodeMs };
  draw();
}

// ---------- drawing ----------
const canvas = $('canvas');
const ctx = canvas.getContext('2d');

function draw() {
  const f = state.frame;
  if (!f) return;
  const overlay = ($('show-depth').checked && f.depth) || ($('show-mask').checked && f.mask);
  // Copy only when an overlay will paint over the colour image.
  const img = new ImageData(overlay ? new Uint8ClampedArray(f.rgba) : f.rgba, f.width, f.height);
  if ($('show-depth').checked && f.depth) {
    let lo = Infinity, hi = 0;
    for (const d of f.depth) if (d) { lo = Math.min(lo, d); hi = Math.max(hi, d); }
    for (let k = 0; k < f.depth.length; k++) {
      const d = f.depth[k];
      const t = d ? (d - lo) / Math.max(1, hi - lo) : 0;
      img.data[4 * k] = d ? 255 * (1 - t) : 0;
      img.data[4 * k + 1] = d ? 120 + 100 * Math.sin(Math.PI * t) : 0;
      img.data[4 * k + 2] = d ? 255 * t : 0;
    }
  }
  if ($('show-mask').checked && f.mask) {
    for (let k = 0; k < f.mask.length; k++) if (f.mask[k]) { img.data[4 * k] = 255; img.data[4 * k + 1] >>= 1; }
  }
  ctx.putImageData(img, 0, 0);
  const i = state.index;
  const info = state.seq.info;
  // What the tracker saw: occlusion rectangles blacked out.
  ctx.fillStyle = 'rgba(0,0,0,0.85)';
  for (const o of info.occlusions) if (i >= o.frames[0] && i <= o.frames[1]) ctx.fillRect(...o.rect);
  for (const r of state.userRects) {
    ctx.fillRect(...r);
    ctx.save(); ctx.strokeStyle = '#ffcc00'; ctx.setLineDash([6, 4]); ctx.strokeRect(...r); ctx.restore();
  }
  const cam = info.camera;
  const gt = info.groundtruth[i];
  if ($('show-truth').checked && gt) {
    ctx.strokeStyle = '#00d000'; ctx.lineWidth = 1.5; ctx.beginPath();
    for (let k = 0; k < gt.length; k += 3) {
      const u = cam.fx * gt[k] / gt[k + 2] + cam.cx, v = cam.fy * gt[k + 1] / gt[k + 2] + cam.cy;
      if (k === 0) ctx.moveTo(u, v); else ctx.lineTo(u, v);
    }
    ctx.stroke();
  }
  const res = state.results[i];
  if (res && res.second) drawNodes(res.second, COMPARED_COLOURS);
  if (res) drawNodes(res, MAIN_COLOURS);
  state.shownAt.push(performance.now());
  if (state.shownAt.length > 30) state.shownAt.shift();
  updateLabels();
  drawPlot();
}

// Node colours: line, visible node, hidden node, error curve.
const MAIN_COLOURS = { line: '#ffffff', visible: '#e02020', hidden: '#ffd000', curve: '#d02020' };
const COMPARED_COLOURS = { line: '#b8f4ff', visible: '#00e0ff', hidden: '#ff4fd8', curve: '#0098b8' };

function drawNodes(res, colours) {
  const p = res.nodesPx;
  if (!p.length) return;
  ctx.strokeStyle = colours.line; ctx.lineWidth = 2; ctx.beginPath();
  for (let k = 0; k < p.length; k += 2) { if (k === 0) ctx.moveTo(p[k], p[k + 1]); else ctx.lineTo(p[k], p[k + 1]); }
  ctx.stroke();
  for (let k = 0; k < p.length / 2; k++) {
    ctx.beginPath(); ctx.arc(p[2 * k], p[2 * k + 1], 4, 0, 2 * Math.PI);
    if (res.visible[k]) { ctx.fillStyle = colours.visible; ctx.fill(); } else { ctx.lineWidth = 2.5; ctx.strokeStyle = colours.hidden; ctx.stroke(); }
  }
}

function mean(xs) { return xs.length ? xs.reduce((a, b) => a + b, 0) / xs.length : NaN; }
function median(xs) { const s = [...xs].sort((a, b) => a - b); return s.length ? s[Math.floor(s.length / 2)] : NaN; }

function updateLabels() {
  const n = state.seq.info.color_files.length;
  $('timeline').value = String(state.index);
  $('frame-label').textContent = `${state.index + 1} / ${n}`;
  const r = state.results[state.index];
  const tracked = state.results.slice(0, state.tracked + 1).filter(Boolean);
  const ts = state.shownAt;
  const fps = ts.length > 1 ? (1000 * (ts.length - 1)) / (ts[ts.length - 1] - ts[0]) : NaN;
  const lines = [
    `sequence ${state.seq.name}   frame ${state.index}   status ${r ? r.status : '-'}${r && r.reason ? ` (${r.reason})` : ''}`,
    r ? `tracking ${r.trackMs.toFixed(2)} ms   segmentation+cloud+tracking ${r.totalMs.toFixed(2)} ms   decoding ${r.decodeMs.toFixed(1)} ms   median tracking ${median(tracked.map((x) => x.trackMs)).toFixed(2)} ms` : '',
    `display ${Number.isFinite(fps) ? fps.toFixed(1) : '-'} frames/s   visible nodes ${r ? r.visible.filter((v) => v).length : '-'} of ${r ? r.visible.length : '-'}`,
    r && r.error.length ? `frame error ${r.error[0].toFixed(2)} mm, ${r.error[1].toFixed(2)} px (${ALGORITHM_NAMES[state.params.algorithm]}, red)` : 'no ground truth for this frame',
  ];
  const c = r && r.second;
  if (c) {
    const err = c.error.length ? `frame error ${c.error[0].toFixed(2)} mm, ${c.error[1].toFixed(2)} px` : 'no ground truth';
    lines.push(`compared: ${ALGORITHM_NAMES[state.compare]} (cyan): ${err}   tracking ${c.trackMs.toFixed(2)} ms   status ${c.status}   median tracking ${median(tracked.filter((x) => x.second).map((x) => x.second.trackMs)).toFixed(2)} ms`);
  }
  $('stats').textContent = lines.join('\n');
}

function drawPlot() {
  const c = $('plot');
  const g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  const n = state.seq.info.color_files.length;
  const series = [{ name: state.params.algorithm, colours: MAIN_COLOURS, of: (r) => r }];
  if (state.compare) series.push({ name: state.compare, colours: COMPARED_COLOURS, of: (r) => r.second });
  for (const s of series) {
    s.errs = state.results.map((r, k) => {
      const x = r && s.of(r);
      return x && x.error.length ? [k, x.error[0], x.error[1]] : null;
    }).filter(Boolean);
  }
  const all = series.flatMap((s) => s.errs);
  if (!all.length) { $('plot-label').textContent = 'Frame error: the sequence has no ground truth.'; return; }
  const ymax = Math.max(10, ...all.map((e) => e[1])) * 1.1;
  const x = (k) => 30 + (k / Math.max(1, n - 1)) * (c.width - 40);
  const y = (v) => c.height - 15 - (v / ymax) * (c.height - 25);
  g.strokeStyle = '#ccc'; g.fillStyle = '#666'; g.font = '10px sans-serif';
  for (const t of [0, ymax / 2, ymax]) { g.beginPath(); g.moveTo(30, y(t)); g.lineTo(c.width - 10, y(t)); g.stroke(); g.fillText(t.toFixed(0), 2, y(t) + 3); }
  const labels = [];
  for (const s of series) {
    if (!s.errs.length) continue;
    g.strokeStyle = s.colours.curve; g.lineWidth = 1.5; g.beginPath();
    s.errs.forEach(([k, v], j) => (j ? g.lineTo(x(k), y(v)) : g.moveTo(x(k), y(v))));
    g.stroke();
    const m = mean(s.errs.map((e) => e[1]));
    g.setLineDash([4, 3]); g.beginPath(); g.moveTo(30, y(m)); g.lineTo(c.width - 10, y(m)); g.stroke(); g.setLineDash([]);
    labels.push(`${ALGORITHM_NAMES[s.name]} mean ${m.toFixed(2)} mm, ${mean(s.errs.map((e) => e[2])).toFixed(2)} px over ${s.errs.length} frames`);
  }
  g.strokeStyle = '#000'; g.beginPath(); g.moveTo(x(state.index), 5); g.lineTo(x(state.index), c.height - 15); g.stroke();
  $('plot-label').textContent = `Frame error (mm) over time (dashed: means). ${labels.join('; ')}.`;
}

// ---------- playback ----------
function updatePlayButton() { $('play').textContent = state.playing ? 'Pause' : 'Play'; }
async function play() {
  if (!state.seq) return;
  state.playing = !state.playing;
  updatePlayButton();
  while (state.playing) {
    const n = state.seq.info.color_files.length;
    if (state.index >= n - 1) { state.playing = false; break; }
    const t0 = performance.now();
    await goTo(state.index + 1);
    const period = 1000 / (state.seq.info.fps * Number($('speed').value));
    const wait = period - (performance.now() - t0);
    if (wait > 0) await new Promise((r) => setTimeout(r, wait));
  }
  updatePlayButton();
}
$('play').onclick = () => play();
$('step').onclick = () => { state.playing = false; goTo(state.index + 1); };
$('step-back').onclick = () => { state.playing = false; goTo(state.index - 1); };
$('timeline').oninput = (e) => { state.playing = false; goTo(Number(e.target.value)); };
document.addEventListener('keydown', (e) => { if (e.code === 'Space' && e.target === document.body) { e.preventDefault(); play(); } });
for (const id of ['show-truth', 'show-mask', 'show-depth']) $(id).onchange = () => goTo(state.index);

// When settings change, the shown frame and those after it are tracked
// again: the worker's tracker goes back to its state before the shown frame.
function invalidateAfterCurrent() {
  state.epoch++;
  const keep = Math.min(state.tracked, state.index - 1);
  if (keep === state.tracked && !state.lookahead) return;
  state.results.length = keep + 1;
  state.tracked = keep;
  const snapshot = keep >= 0 ? state.results[keep].snapshot : null;
  state.busy = state.busy.then(() => call({ type: 'restore', snapshot }));
}

// ---------- parameters ----------
function setParamInputs(p) {
  for (const f of PARAM_FIELDS) $(`p-${f}`).value = MM_FIELDS.has(f) ? Math.round(p[f] * 1e4) / 10 : p[f];
}
$('params').onchange = guarded(async () => {
  const next = { ...state.params };
  for (const f of PARAM_FIELDS) {
    const v = Number($(`p-${f}`).value);
    next[f] = MM_FIELDS.has(f) ? v / 1000 : v;
  }
  try {
    const r = await call({ type: 'params', params: next });
    state.params = r.params;
    invalidateAfterCurrent();
    await goTo(state.index);
  } catch (err) {
    setParamInputs(state.params);
    throw err;
  }
});
function hsvInputs() {
  return { lower: ['h', 's', 'v'].map((c) => Number($(`${c}-lo`).value)), upper: ['h', 's', 'v'].map((c) => Number($(`${c}-hi`).value)) };
}
// A new algorithm (or compared one) tracks the sequence again from the start.
$('algorithms').onchange = guarded(async () => {
  state.params = { ...state.params, algorithm: $('algorithm').value };
  state.compare = $('compare').value;
  if (!state.seq) return;
  state.playing = false;
  updatePlayButton();
  state.generation++;
  state.epoch++;
  const seq = state.seq;
  state.busy = state.busy.then(async () => {
    await call({ type: 'open', camera: seq.info.camera, params: state.params, hsv: hsvInputs(), compare: state.compare });
    state.results = [];
    state.tracked = -1;
    state.lookahead = null;
  });
  await state.busy;
  await goTo(state.index);
});
function setHsvInputs(h) {
  ['h', 's', 'v'].forEach((c, k) => { $(`${c}-lo`).value = h.lower[k]; $(`${c}-hi`).value = h.upper[k]; });
}
$('hsv').onchange = guarded(async () => {
  const { lower, upper } = hsvInputs();
  await call({ type: 'hsv', lower, upper });
  invalidateAfterCurrent();
  await goTo(state.index);
});

// OpenCV's 8-bit HSV of one pixel, for the colour picker.
function rgbToHsv(r, g, b) {
  const v = Math.max(r, g, b), mn = Math.min(r, g, b), d = v - mn;
  const s = v ? Math.round((d * 255) / v) : 0;
  let h = 0;
  if (d) {
    if (v === r) h = (60 * (g - b)) / d; else if (v === g) h = 120 + (60 * (b - r)) / d; else h = 240 + (60 * (r - g)) / d;
    if (h < 0) h += 360;
  }
  return [Math.round(h / 2) % 180, s, v];
}

// ---------- mouse: occlusion rectangles and colour picking ----------
function imagePoint(e) {
  const b = canvas.getBoundingClientRect();
  return [Math.round(((e.clientX - b.left) / b.width) * canvas.width), Math.round(((e.clientY - b.top) / b.height) * canvas.height)];
}
function setMode(mode) {
  state.mode = state.mode === mode ? 'none' : mode;
  $('draw-mode').classList.toggle('active', state.mode === 'draw');
  $('pick-mode').classList.toggle('active', state.mode === 'pick');
  canvas.classList.toggle('drawing', state.mode === 'draw');
  canvas.classList.toggle('picking', state.mode === 'pick');
}
$('draw-mode').onclick = () => setMode('draw');
$('pick-mode').onclick = () => setMode('pick');
let dragStart = null;
canvas.onmousedown = (e) => { if (state.mode === 'draw') dragStart = imagePoint(e); };
canvas.onmousemove = (e) => {
  if (!dragStart) return;
  draw();
  const [x, y] = imagePoint(e);
  ctx.strokeStyle = '#ffcc00'; ctx.setLineDash([6, 4]);
  ctx.strokeRect(dragStart[0], dragStart[1], x - dragStart[0], y - dragStart[1]);
  ctx.setLineDash([]);
};
canvas.onmouseup = (e) => {
  if (state.mode === 'pick' && state.frame) {
    const [x, y] = imagePoint(e);
    const k = 4 * (y * state.frame.width + x);
    const [h, s, v] = rgbToHsv(state.frame.rgba[k], state.frame.rgba[k + 1], state.frame.rgba[k + 2]);
    setHsvInputs({ lower: [(h + 168) % 180, Math.max(40, s - 70), Math.max(20, v - 90)], upper: [(h + 12) % 180, 255, 255] });
    setMode('pick');
    $('hsv').onchange();
    return;
  }
  if (!dragStart) return;
  const [x, y] = imagePoint(e);
  const r = [Math.min(x, dragStart[0]), Math.min(y, dragStart[1]), Math.abs(x - dragStart[0]), Math.abs(y - dragStart[1])];
  dragStart = null;
  if (r[2] > 2 && r[3] > 2) addRect(r);
};
function addRect(r) {
  state.userRects.push(r);
  renderRects();
  invalidateAfterCurrent();
  goTo(state.index);
}
function renderRects() {
  const box = $('rects');
  box.textContent = '';
  state.userRects.forEach((r, k) => {
    const b = document.createElement('button');
    b.textContent = `× [${r.join(', ')}]`;
    b.title = 'Remove this occlusion';
    b.onclick = () => { state.userRects.splice(k, 1); renderRects(); invalidateAfterCurrent(); goTo(state.index); };
    box.append(b);
  });
}
$('clear-rects').onclick = () => { state.userRects = []; renderRects(); invalidateAfterCurrent(); goTo(state.index); };

// ---------- export ----------
function resultJson() {
  return {
    algorithm: state.params.algorithm,
    params: state.params,
    frames: state.results.slice(0, state.tracked + 1).map((r, k) => {
      const f = { frame: k, nodes: [], visible: r.visible.map((v) => v === 1), track_ms: r.trackMs, total_ms: r.totalMs };
      for (let j = 0; j < r.nodes.length; j += 3) f.nodes.push([r.nodes[j], r.nodes[j + 1], r.nodes[j + 2]]);
      if (r.status === 'lost') { f.lost = true; f.reason = r.reason; }
      return f;
    }),
  };
}
$('export').onclick = guarded(async () => {
  if (!state.seq) return;
  const here = state.index;
  await goTo(state.seq.info.color_files.length - 1);
  await goTo(here);
  const blob = new Blob([JSON.stringify(resultJson())], { type: 'application/json' });
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = `${state.seq.name.replace(/\.zip$/i, '')}.result.json`;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
});

// ---------- start ----------
const query = new URLSearchParams(location.search);
if (query.get('embed') === '1') document.body.classList.add('embed');
$('embed-snippet').textContent =
  `<iframe src="${new URL('index.html?sample=static-s&autoplay=1&embed=1', location.href)}" width="680" height="600" style="border:0"></iframe>`;

async function start() {
  const { params } = await call({ type: 'defaults' });
  for (const [k, v] of query) if (k.startsWith('p.') && typeof params[k.slice(2)] === 'number') params[k.slice(2)] = Number(v);
  if (query.get('algorithm') in ALGORITHM_NAMES) params.algorithm = query.get('algorithm');
  if (query.get('compare') in ALGORITHM_NAMES) state.compare = query.get('compare');
  $('algorithm').value = params.algorithm;
  $('compare').value = state.compare;
  state.params = params;
  setParamInputs(params);
  if (query.has('speed')) $('speed').value = query.get('speed');
  const r = await fetch(new URL('../samples/index.json', import.meta.url));
  if (!r.ok) throw new Error(`samples/index.json: HTTP ${r.status} (run scripts/build-web.sh)`);
  const index = await r.json();
  const select = $('sample');
  for (const s of index.samples) select.append(new Option(s.name, s.name));
  select.onchange = guarded(() => loadSample(select.value, index));
  const first = query.get('sample') || (index.samples.find((s) => s.name === 'static-s') || index.samples[0]).name;
  select.value = first;
  await loadSample(first, index);
  if (query.get('autoplay') !== '0') play();
}

// Hooks for the browser tests and for scripting the page.
window.upetrack = {
  state,
  goTo,
  resultJson,
  addRect,
  trackAll: async () => { await goTo(state.seq.info.color_files.length - 1); return resultJson(); },
  ready: guarded(start)(),
};
