// The side panels and the mouse on the image: the algorithm choice, the
// parameters, the HSV range (typed or picked by clicking the rope) and the
// drawn occlusion rectangles. Every value is checked by the core before use.
import { state, $, guarded, settleLookahead, afterBusy } from './state.js';
import { call } from './worker-client.js';
import { Request } from './protocol.js';
import { canvas, draw, drawDragged } from './draw.js';
import { goTo, retrackFromHere, updatePlayButton } from './playback.js';
import { checkDlo, hsvRangeAround, parseParams, defaultParams } from './core.js';
import { chooseRopeAt } from './rope.js';
import { setParamInputs, paramsFromInputs, showGroupsFor } from './params-panel.js';
import { shareLink } from './share.js';

export function setHsvInputs(h) {
  ['h', 's', 'v'].forEach((c, k) => { $(`${c}-lo`).value = h.lower[k]; $(`${c}-hi`).value = h.upper[k]; });
  $('chroma-noise').value = h.chroma_noise || 0;
}

// The typed range, checked as dlo.json's `segmentation` would be.
function hsvFromInputs() {
  const [lower, upper] = ['lo', 'hi'].map((end) => ['h', 's', 'v'].map((c) => Number($(`${c}-${end}`).value)));
  const segmentation = { hsv_lower: lower, hsv_upper: upper, chroma_noise: Number($('chroma-noise').value) };
  return checkDlo(JSON.stringify({ segmentation })).hsv;
}

export async function applyHsv(hsv) {
  await call(Request.hsv(hsv));
  state.hsv = hsv;
  await retrackFromHere();
}

export function renderRects() {
  const box = $('rects');
  box.textContent = '';
  state.userRects.forEach((r, k) => {
    const b = document.createElement('button');
    b.textContent = `× [${r.join(', ')}]`;
    b.title = 'Remove this occlusion';
    b.onclick = () => { state.userRects.splice(k, 1); renderRects(); retrackFromHere(); };
    box.append(b);
  });
}

// Adds a drawn rectangle ([x, y, w, h], whole pixels) for every frame.
export function addRect(r) {
  const last = state.seq ? state.seq.info.color_files.length - 1 : 0;
  checkDlo(JSON.stringify({ occlusions: [{ frames: [0, last], rect: r }] }));
  state.userRects.push(r);
  renderRects();
  return retrackFromHere();
}

function imagePoint(e) {
  const b = canvas.getBoundingClientRect();
  return [Math.round(((e.clientX - b.left) / b.width) * canvas.width), Math.round(((e.clientY - b.top) / b.height) * canvas.height)];
}

// Toggles `mode` ('draw' or 'pick'); `on` forces it on.
export function setMode(mode, on = false) {
  state.mode = state.mode === mode && !on ? 'none' : mode;
  $('draw-mode').classList.toggle('active', state.mode === 'draw');
  $('pick-mode').classList.toggle('active', state.mode === 'pick');
  $('add-rope-mode').classList.toggle('active', state.mode === 'add');
  canvas.classList.toggle('drawing', state.mode === 'draw');
  canvas.classList.toggle('picking', state.mode === 'pick' || state.mode === 'add');
}

// The colour range around the pixel at (x, y) of the shown frame, and the
// rope through it: where several shapes look like a rope, the one clicked.
export function pickAt(x, y) {
  const f = state.frame;
  const k = 4 * (y * f.width + x);
  const hsv = hsvRangeAround(f.rgba[k], f.rgba[k + 1], f.rgba[k + 2]);
  setHsvInputs(hsv);
  if (state.webcam || !state.seq) return applyHsv(hsv);
  return chooseRopeAt(x, y, hsv);
}

// Another rope tracked too: the one through (x, y) of the shown frame, in
// the colour range around that pixel; the ropes are found again from here.
export async function addRopeAt(x, y) {
  if (state.webcam || !state.seq) throw new Error('open a sequence first: ropes are added to a sequence');
  const f = state.frame;
  const k = 4 * (y * f.width + x);
  const hsv = hsvRangeAround(f.rgba[k], f.rgba[k + 1], f.rgba[k + 2]);
  const { ropes } = await afterBusy(async () => {
    await settleLookahead();
    return call(Request.addRope(hsv, [x, y]));
  });
  const info = state.seq.info;
  const known = info.ropes && info.ropes.length ? info.ropes : [{ groundtruth: info.groundtruth }];
  info.ropes = ropes.map((r, k) => ({ ...r, groundtruth: known[k] ? known[k].groundtruth : [] }));
  // The frames before this one keep what was tracked; the new rope was not
  // tracked on them (a lost record saying so).
  const from = state.index;
  state.results.forEach((r, i) => {
    if (!r) return;
    if (!r.ropes.length) r.ropes = [{ name: ropes[0].name, nodes: r.nodes, nodesPx: r.nodesPx, visible: r.visible, status: r.status, reason: r.reason, record: r.record, error: r.error }];
    while (r.ropes.length < ropes.length) {
      const reason = `not tracked yet: added on frame ${from}`;
      r.ropes.push({
        name: ropes[r.ropes.length].name, nodes: [], nodesPx: [], visible: [], status: 'lost', reason, error: [],
        record: { frame: i, nodes: [], visible: [], track_ms: 0, total_ms: 0, lost: true, reason },
      });
    }
  });
  return retrackFromHere(true);
}

export function bindPanels() {
  const applyParams = async (next) => {
    try {
      const checked = parseParams(JSON.stringify(next));
      const r = await call(Request.params(checked));
      state.params = r.params;
      setParamInputs(state.params);
      await retrackFromHere();
    } catch (err) {
      setParamInputs(state.params);
      throw err;
    }
  };
  $('params').onchange = guarded(() => applyParams(paramsFromInputs(state.params)));
  $('reset-params').onclick = guarded(() => applyParams({ ...defaultParams(), algorithm: state.params.algorithm }));
  $('share-link').onclick = guarded(() => {
    const url = shareLink();
    history.replaceState(null, '', url);
    $('share-url').hidden = false;
    $('share-url').value = url;
    $('share-url').select();
  });
  // A new algorithm (or compared one) tracks the sequence again from the start.
  $('algorithms').onchange = guarded(async () => {
    state.params = { ...state.params, algorithm: $('algorithm').value };
    state.compare = $('compare').value;
    showGroupsFor([state.params.algorithm, state.compare]);
    if (!state.seq) return;
    state.playing = false;
    updatePlayButton();
    state.generation++;
    state.epoch++;
    const seq = state.seq;
    state.busy = state.busy.then(async () => {
      await settleLookahead();
      await call(Request.open(seq.info.camera, seq.info.fps, state.params, state.hsv, state.rope, state.compare, seq.info.ropes || []));
      state.results = [];
      state.tracked = -1;
    });
    await state.busy;
    await goTo(state.index);
  });
  $('hsv').onchange = guarded(async () => {
    try {
      await applyHsv(hsvFromInputs());
    } catch (err) {
      if (state.hsv) setHsvInputs(state.hsv);
      throw err;
    }
  });
  $('draw-mode').onclick = () => setMode('draw');
  $('pick-mode').onclick = () => setMode('pick');
  $('add-rope-mode').onclick = () => setMode('add');
  $('clear-rects').onclick = () => { state.userRects = []; renderRects(); retrackFromHere(); };
  let dragStart = null;
  canvas.onmousedown = (e) => { if (state.mode === 'draw') dragStart = imagePoint(e); };
  canvas.onmousemove = (e) => { if (dragStart) drawDragged(dragStart, imagePoint(e)); };
  canvas.onmouseup = guarded(async (e) => {
    if ((state.mode === 'pick' || state.mode === 'add') && state.frame) {
      const [x, y] = imagePoint(e);
      const adding = state.mode === 'add';
      setMode(state.mode);
      // The hint has been followed: it goes before the re-tracking starts.
      if (state.note) $('message').hidden = true;
      await (adding ? addRopeAt(x, y) : pickAt(x, y));
      return;
    }
    if (!dragStart) return;
    const [x, y] = imagePoint(e);
    const r = [Math.min(x, dragStart[0]), Math.min(y, dragStart[1]), Math.abs(x - dragStart[0]), Math.abs(y - dragStart[1])];
    dragStart = null;
    if (r[2] > 2 && r[3] > 2) await addRect(r); else draw();
  });
}
