// The page's state and its small shared helpers: element lookup, the
// message banner, the progress bar, and error guarding of handlers.

export const $ = (id) => document.getElementById(id);

export const ALGORITHM_NAMES = { upetrack: 'UPETrack', cpd: 'CPD', trackdlo: 'TrackDLO', cdcpd2: 'CDCPD2' };

export const state = {
  seq: null,          // { name, info, read(path), fromZip, fromRecording, details, configured }
  sampleName: null,   // the bundled sample last opened, for a shared link
  index: 0,           // frame shown
  tracked: -1,        // last frame tracked (frames are tracked in order)
  results: [],        // per frame: { nodes, nodesPx, visible, status, reason, init, segmentMs, cloudMs, trackMs, totalMs, decodeMs, error, snapshot, second }
  params: null,       // parameters in force (all fields, with the algorithm)
  compare: '',        // algorithm tracked alongside for comparison ('' for none)
  hsv: null,          // { lower, upper } in force
  rope: null,         // dlo.json's rope in force ({ length_m, diameter_m }), or null
  userRects: [],      // [x, y, w, h] drawn on the image
  playing: false,
  busy: Promise.resolve(),
  frame: null,        // last decoded frame { width, height, rgba, mask, depth, decodeMs }
  truthPx: null,      // ground truth of the shown frame in pixels
  truthsPx: [],       // with several ropes, each one's
  mode: 'none',       // 'draw' | 'pick'
  explain: null,      // the explain mode: { index, steps, at, view, frame }, or null
  webcam: null,       // the webcam mode: { stream, video, frames, depthScale }, or null
  shownAt: [],        // display timestamps, for the frame rate
  generation: 0,      // bumped when a new sequence opens
  epoch: 0,           // bumped when settings change; a look-ahead from an older epoch is dropped
  lookahead: [],      // [{ index, epoch, generation, promise }] of the next frames, while playing
  decoder: 'wasm',    // colour decoded by 'wasm' (as the command does), 'browser' (ImageDecoder) or 'canvas' (createImageBitmap)
  errors: [],         // every message shown in the banner, for scripts and tests
  note: false,        // the banner shows a hint (showNote), not an error
};

// Runs `fn` once the work queued on the page is done, and queues what comes
// later after it: a change of settings is never interleaved with frames
// being tracked, and a script waiting on `state.busy` waits for it too.
export function afterBusy(fn) {
  const step = state.busy.then(fn);
  state.busy = step.catch(() => {});
  return step;
}

// Waits for every frame requested ahead to come back (tracked by the worker
// with the state it had) and forgets them: a restore or a new tracker sent
// after this cannot overtake them.
export async function settleLookahead() {
  const pending = state.lookahead.map((l) => l.promise.catch(() => {}));
  state.lookahead = [];
  await Promise.all(pending);
}

export function showError(text) {
  state.note = false;
  $('message-text').textContent = text;
  $('message').hidden = false;
  state.errors.push(text);
  console.error(text);
}

// A hint in the banner that is not an error.
export function showNote(text) {
  state.note = true;
  $('message-text').textContent = text;
  $('message').hidden = false;
}

export function progress(value, max) {
  const p = $('progress');
  if (value === null) { p.hidden = true; return; }
  p.hidden = false;
  if (max) { p.max = max; p.value = value; } else p.removeAttribute('value');
}

// A handler whose failures are shown in the banner instead of thrown.
export function guarded(fn) {
  return async (...args) => {
    try { return await fn(...args); } catch (err) { progress(null); showError(err.message || String(err)); return undefined; }
  };
}
