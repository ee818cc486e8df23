// The demo page: wiring only. Sequence loading (sequence.js), playback
// (playback.js), drawing (draw.js), the plot (plot.js), the panels
// (panels.js) and export (export.js) run the tracker in a Web Worker
// (worker.js, protocol.js); the core's rules come through core.js.
import { state, $, guarded, showError, showNote, ALGORITHM_NAMES } from './state.js';
import { call } from './worker-client.js';
import { Request } from './protocol.js';
import { ready as coreReady } from './core.js';
import { hooks, loadSample, openFiles, openZip, openRecording, kindOf, entryFiles } from './sequence.js';
import { goTo, play, updatePlayButton, SPEEDS } from './playback.js';
import { bindPanels, setHsvInputs, renderRects, addRect, pickAt, setMode, applyHsv } from './panels.js';
import { buildParamPanel, setParamInputs, applyParamsQuery, showGroupsFor } from './params-panel.js';
import { parseHsvQuery, parseRectsQuery } from './share.js';
import { checkDlo } from './core.js';
import { resultJson, dloJson, download } from './export.js';
import { pageStats } from './plot.js';
import { explainFrame, moveStep, stepName } from './explain.js';
import { bindScenePanel } from './scenes.js';
import { startWebcam, stopWebcam } from './webcam.js';
import { bindRopePanel, setRopeInputs } from './rope.js';

hooks.opened = async () => {
  const info = state.seq.info;
  updatePlayButton();
  renderRects();
  setHsvInputs(info.hsv);
  setRopeInputs(info.rope);
  $('timeline').max = String(info.color_files.length - 1);
  $('canvas').width = info.camera.width;
  $('canvas').height = info.camera.height;
  await goTo(0);
  const d = state.seq.details;
  $('seq-details').textContent = d
    ? `${d.layout} recording: ${d.paired_frames} frames ${d.color.width}x${d.color.height}, depth ${d.aligned_on_reading ? 'aligned to colour here' : 'already aligned'}` +
      (d.unpaired_color + d.unpaired_depth ? `; ${d.unpaired_color} colour and ${d.unpaired_depth} depth frames unpaired` : '') +
      (d.warnings.length ? `; ${d.warnings.join('; ')}` : '')
    : '';
  // A recording has no dlo.json: the rope's colour is picked by a click.
  if (state.seq.fromRecording && !state.seq.configured) {
    setMode('pick', true);
    showNote('Click the rope to take its colour; save the setup with "Save dlo.json".');
  }
};

hooks.closing = stopWebcam;
// The same button stops the camera; the sample list reopens a sequence.
$('webcam').onclick = guarded(() => (state.webcam ? stopWebcam() : startWebcam((hsv) => {
  updatePlayButton();
  renderRects();
  setHsvInputs(hsv);
  setMode('pick', true);
  $('seq-details').textContent = '';
})));

$('message-close').onclick = () => { $('message').hidden = true; };

// ---------- opening ----------
$('folder').onchange = guarded(async (e) => {
  const files = [...e.target.files].map((f) => ({ path: f.webkitRelativePath || f.name, file: f }));
  e.target.value = '';
  if (!files.length) throw new Error('The folder is empty.');
  await openFiles(files, 'folder');
});
$('recording').onchange = guarded(async (e) => {
  const files = [...e.target.files];
  e.target.value = '';
  const kinds = await Promise.all(files.map(kindOf));
  const i = kinds.findIndex((k) => k.kind === 'recording');
  if (i < 0) {
    const said = files.length === 1 ? `${files[0].name} is ${kinds[0].what}, not a recording. ` : '';
    throw new Error(`${said}Pick a .bag, .db3 or .mcap recording (and, optionally, its dlo.json).`);
  }
  await openRecording(files[i], files.find((f, k) => k !== i && /\.json$/i.test(f.name)) || null);
});
$('zip').onchange = guarded(async (e) => {
  const f = e.target.files[0];
  e.target.value = '';
  if (!f) return;
  const k = await kindOf(f);
  if (k.kind !== 'zip') throw new Error(`${f.name} is ${k.what}, not a .zip of a sequence folder.`);
  await openZip(f);
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

// ---------- explain mode ----------
async function openExplain(i, step = null) {
  state.playing = false;
  updatePlayButton();
  $('explain-panel').hidden = false;
  $('explain').classList.add('active');
  // A link's step must exist; moving to another frame keeps the nearest step.
  if (step) await explainFrame(i, step, goTo, true);
  else await explainFrame(i, stepName(), goTo, false);
}
function closeExplain() {
  state.explain = null;
  $('explain-panel').hidden = true;
  $('explain').classList.remove('active');
  goTo(state.index);
}
$('explain').onclick = guarded(() => (state.explain ? closeExplain() : openExplain(state.index)));
$('explain-close').onclick = () => closeExplain();
$('explain-back').onclick = () => moveStep(-1);
$('explain-next').onclick = () => moveStep(1);
$('explain-rope').onchange = guarded(() => state.explain && openExplain(state.explain.index));
document.addEventListener('keydown', (e) => {
  if (!state.explain || e.target !== document.body) return;
  if (e.code === 'ArrowLeft') { e.preventDefault(); moveStep(-1); }
  if (e.code === 'ArrowRight') { e.preventDefault(); moveStep(1); }
});

// ---------- transport ----------
$('play').onclick = () => { if (state.explain) closeExplain(); play(); };
// While explaining, moving to another frame explains that one.
const moveTo = guarded((i) => (state.explain ? openExplain(Math.max(0, Math.min(state.seq.info.color_files.length - 1, i))) : goTo(i)));
$('step').onclick = () => { state.playing = false; moveTo(state.index + 1); };
$('step-back').onclick = () => { state.playing = false; moveTo(state.index - 1); };
$('timeline').oninput = (e) => { state.playing = false; moveTo(Number(e.target.value)); };
document.addEventListener('keydown', (e) => { if (e.code === 'Space' && e.target === document.body) { e.preventDefault(); play(); } });
for (const id of ['show-truth', 'show-mask', 'show-depth']) $(id).onchange = () => goTo(state.index);
bindPanels();
bindRopePanel(guarded);

$('export').onclick = guarded(async () => {
  if (!state.seq) return;
  const here = state.index;
  await goTo(state.seq.info.color_files.length - 1);
  await goTo(here);
  download(`${state.seq.name.replace(/\.zip$/i, '')}.result.json`, resultJson());
});

$('save-dlo').onclick = guarded(async () => {
  if (!state.seq) return;
  download(`${state.seq.name.replace(/\.(zip|bag|db3|mcap)$/i, '')}.dlo.json`, dloJson());
});

// ---------- start ----------
const query = new URLSearchParams(location.search);
if (query.get('embed') === '1') document.body.classList.add('embed');
$('embed-snippet').textContent =
  `<iframe src="${new URL('index.html?sample=static-s&autoplay=1&embed=1', location.href)}" width="680" height="600" style="border:0"></iframe>`;

// Who decodes colour files: WebAssembly (the default: the command's decoder,
// bit for bit, and the fastest on the machines measured, docs/testing.md),
// the browser (ImageDecoder, or createImageBitmap where there is none), or
// createImageBitmap always ('canvas').
const DECODERS = ['wasm', 'browser', 'canvas'];

// `speed=` must be one of the offered speeds; anything else is refused.
function applySpeed(text) {
  const v = Number(text);
  if (!SPEEDS.includes(v)) throw new Error(`speed=${text} is not one of ${SPEEDS.join(', ')}`);
  $('speed').value = String(v);
}

async function start() {
  await coreReady;
  buildParamPanel();
  bindScenePanel();
  const { params } = await call(Request.defaults());
  const problems = applyParamsQuery(query, params);
  if (query.has('decode')) {
    if (DECODERS.includes(query.get('decode'))) state.decoder = query.get('decode');
    else problems.push(`decode=${query.get('decode')} is not one of ${DECODERS.join(', ')}`);
  }
  if (query.get('algorithm') in ALGORITHM_NAMES) params.algorithm = query.get('algorithm');
  if (query.get('explain') === 'upe') params.algorithm = 'upetrack';
  if (query.get('compare') in ALGORITHM_NAMES) state.compare = query.get('compare');
  $('algorithm').value = params.algorithm;
  $('compare').value = state.compare;
  try {
    state.params = (await call(Request.params(params))).params;
  } catch (err) {
    problems.push(err.message);
    state.params = (await call(Request.defaults())).params;
  }
  setParamInputs(state.params);
  showGroupsFor([state.params.algorithm, state.compare]);
  if (query.has('speed')) {
    try { applySpeed(query.get('speed')); } catch (err) { problems.push(err.message); }
  }
  let hsv = null;
  let rects = [];
  try {
    if (query.has('hsv')) {
      const h = parseHsvQuery(query.get('hsv'));
      hsv = checkDlo(JSON.stringify({ segmentation: { hsv_lower: h.lower, hsv_upper: h.upper, chroma_noise: h.chroma_noise } })).hsv;
    }
    if (query.has('rects')) rects = parseRectsQuery(query.get('rects'));
  } catch (err) { problems.push(err.message); }
  if (problems.length) showError(problems.join('; '));
  const r = await fetch(new URL('../samples/index.json', import.meta.url));
  if (!r.ok) throw new Error(`samples/index.json: HTTP ${r.status} (run scripts/build-web.sh)`);
  const index = await r.json();
  const select = $('sample');
  for (const s of index.samples) select.append(new Option(s.name, s.name));
  select.onchange = guarded(() => loadSample(select.value, index));
  const first = query.get('sample') || (index.samples.find((s) => s.name === 'dynamic-pull') || index.samples[0]).name;
  select.value = first;
  await loadSample(first, index);
  // A shared link's colour range and drawn occlusions, over the sample's own.
  if (hsv) { setHsvInputs(hsv); await applyHsv(hsv); }
  for (const rect of rects) {
    try { await addRect(rect); } catch (err) { showError(err.message); }
  }
  // A deep link into the explain mode: ?explain=upe&frame=N&step=S.
  if (query.has('explain')) {
    if (query.get('explain') !== 'upe') throw new Error(`explain=${query.get('explain')}: the explain mode shows UPETrack's step (explain=upe)`);
    const frame = query.has('frame') ? Number(query.get('frame')) : 0;
    if (!Number.isInteger(frame)) throw new Error(`frame=${query.get('frame')} is not a frame number`);
    await openExplain(frame, query.get('step'));
    return;
  }
  if (query.get('autoplay') !== '0') play();
  // The opening look: a page opened as it is (no sample, no settings)
  // loops its sample, five seconds of a rope pulled under an occluder.
  if (query.has('loop')) $('loop').checked = query.get('loop') === '1';
  else if (!query.has('sample') && !query.has('autoplay')) $('loop').checked = true;
}

// Hooks for the browser tests and for scripting the page.
window.upetrack = {
  // { fps, decode_ms, track_ms, total_ms, frames }: medians over the last 60 frames.
  get stats() { return pageStats(); },
  state,
  goTo,
  resultJson,
  addRect,
  pickAt,
  dloJson,
  // Every frame tracked under the settings in force (a change made meanwhile
  // tracks again from where it applies), then the result.
  trackAll: async () => {
    const last = state.seq.info.color_files.length - 1;
    for (let tries = 0; tries < 4 && state.tracked < last; tries++) { await goTo(last); await state.busy; }
    return resultJson();
  },
  ready: guarded(start)(),
};
