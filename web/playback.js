// Moving through a sequence: frames are tracked in order, each result keeps
// the tracker's snapshot, and while playing the next frames are requested
// before the current one is drawn (the worker works while the page draws).
import { state, $, showError, progress, settleLookahead } from './state.js';
import { call } from './worker-client.js';
import { Request } from './protocol.js';
import { requestFrame } from './sequence.js';
import { draw } from './draw.js';
import { updateLabels, drawPlot, updateStatsPanel, pageStats, STATS_WINDOW } from './plot.js';
import { projectPoints } from './core.js';
import { showStep } from './explain.js';
import { noteRopeFinding } from './rope.js';

// Frames requested ahead of the shown one while playing.
export const LOOKAHEAD = 2;

// Playback speeds offered (the page's select), times the sequence's fps.
export const SPEEDS = [0.25, 0.5, 1, 2, 4];

export function updatePlayButton() { $('play').textContent = state.playing ? 'Pause' : 'Play'; }

// Draws the shown frame with its labels and the plot.
export function render() {
  if (state.explain && state.explain.index === state.index) showStep(); else draw();
  state.shownAt.push(performance.now());
  if (state.shownAt.length > STATS_WINDOW) state.shownAt.shift();
  const stats = pageStats();
  updateLabels(stats);
  updateStatsPanel(stats);
  drawPlot();
}

// Shows frame i, tracking every frame up to it first (tracking is sequential).
export function goTo(i) {
  state.busy = state.busy.then(() => goToNow(i)).catch((err) => {
    state.playing = false;
    updatePlayButton();
    showError(err.message || String(err));
  });
  return state.busy;
}

// What the page keeps of a frame's reply.
export function keep(r) {
  return {
    nodes: r.nodes, nodesPx: r.nodesPx, visible: r.visible, status: r.status, reason: r.reason, init: r.init || null,
    segmentMs: r.segmentMs, cloudMs: r.cloudMs, trackMs: r.trackMs, totalMs: r.totalMs, decodeMs: r.decodeMs,
    error: r.error, snapshot: r.snapshot, record: r.record,
    second: r.second || null, ropes: r.ropes || [],
  };
}

async function goToNow(i) {
  if (!state.seq || state.seq.live) return;
  const n = state.seq.info.color_files.length;
  i = Math.max(0, Math.min(n - 1, i));
  const generation = state.generation;
  // Settings changed while these frames were tracked: what follows was
  // tracked under the old ones, and the page tracks again from the kept frame.
  const epoch = state.epoch;
  let r = null;
  if (i <= state.tracked) {
    r = await requestFrame(i, false);
  } else {
    const from = state.tracked + 1;
    for (let k = from; k <= i; k++) {
      const look = state.lookahead.shift();
      const usable = look && look.index === k && look.epoch === state.epoch && look.generation === generation;
      if (!usable && look) await settleLookahead();
      r = await (usable ? look.promise : requestFrame(k, true));
      if (generation !== state.generation || epoch !== state.epoch) return;
      state.results[k] = keep(r);
      state.tracked = k;
      noteRopeFinding(k, r);
      if (state.playing && k === i) {
        // Keep LOOKAHEAD frames requested: the worker decodes the later
        // ones while it tracks the earlier, and while this one is drawn.
        let next = state.lookahead.length ? state.lookahead[state.lookahead.length - 1].index + 1 : k + 1;
        for (; next < n && next <= k + LOOKAHEAD; next++) {
          const promise = requestFrame(next, true);
          promise.catch(() => {});
          state.lookahead.push({ index: next, epoch: state.epoch, generation, promise });
        }
      }
      if (k < i && (k - from) % 10 === 9) progress(k - from, i - from);
    }
    progress(null);
  }
  if (generation !== state.generation || epoch !== state.epoch) return;
  state.index = i;
  state.frame = {
    width: r.width, height: r.height, rgba: new Uint8ClampedArray(r.rgba),
    mask: r.mask ? new Uint8Array(r.mask) : null, depth: r.depth ? new Uint8ClampedArray(r.depth) : null, decodeMs: r.decodeMs,
  };
  const gt = state.seq.info.groundtruth[i];
  state.truthPx = gt ? projectPoints(state.seq.info.camera, new Float64Array(gt)) : null;
  // Several ropes: every rope's truth.
  state.truthsPx = (state.seq.info.ropes || []).map((r) => r.groundtruth[i])
    .filter(Boolean).map((t) => projectPoints(state.seq.info.camera, new Float64Array(t)));
  render();
}

export async function play() {
  if (!state.seq || state.seq.live) return;
  state.playing = !state.playing;
  updatePlayButton();
  while (state.playing) {
    const n = state.seq.info.color_files.length;
    const wrap = state.index >= n - 1;
    if (wrap && !$('loop').checked) { state.playing = false; break; }
    const t0 = performance.now();
    await goTo(wrap ? 0 : state.index + 1);
    const period = 1000 / (state.seq.info.fps * Number($('speed').value));
    const wait = period - (performance.now() - t0);
    if (wait > 0) await new Promise((r) => setTimeout(r, wait));
  }
  updatePlayButton();
}

// When settings change, the shown frame and those after it are tracked
// again: the worker's tracker goes back to its state before the shown frame
// or, `fresh`, to no state (the rope is found again on the shown frame).
export function invalidateAfterCurrent(fresh = false) {
  state.epoch++;
  const kept = Math.min(state.tracked, state.index - 1);
  if (!fresh && kept === state.tracked && !state.lookahead.length) return;
  state.results.length = kept + 1;
  state.tracked = kept;
  const snapshot = !fresh && kept >= 0 ? state.results[kept].snapshot : null;
  state.busy = state.busy.then(settleLookahead).then(() => call(Request.restore(snapshot)));
}

// Re-tracks from the shown frame after a settings change, and shows it.
export function retrackFromHere(fresh = false) {
  invalidateAfterCurrent(fresh);
  return goTo(state.index);
}
