// The frame-error plot and the statistics lines under the image. Means and
// medians come from the core (errorStats), as in `upetrack eval`.
import { state, $, ALGORITHM_NAMES } from './state.js';
import { MAIN_COLOURS, COMPARED_COLOURS, ROPE_COLOURS } from './draw.js';
import { errorStats } from './core.js';

const stats = (xs) => errorStats(new Float64Array(xs));
const fixed = (x, d) => (Number.isFinite(x) ? x.toFixed(d) : '-');

// Frames the page's statistics look back over.
export const STATS_WINDOW = 60;

// `window.upetrack.stats`: medians over the last STATS_WINDOW frames up to
// the one shown. `fps` is the display rate (from the median interval between
// frames drawn), the times are the worker's for each frame.
export function pageStats() {
  const ts = state.shownAt;
  const intervals = ts.slice(1).map((t, k) => t - ts[k]);
  const recent = state.results.slice(Math.max(0, state.index - STATS_WINDOW + 1), state.index + 1).filter(Boolean);
  const median = (xs) => (xs.length ? stats(xs).median : NaN);
  return {
    fps: intervals.length ? 1000 / median(intervals) : NaN,
    decode_ms: median(recent.map((r) => r.decodeMs)),
    segment_ms: median(recent.map((r) => r.segmentMs)),
    cloud_ms: median(recent.map((r) => r.cloudMs)),
    track_ms: median(recent.map((r) => r.trackMs)),
    total_ms: median(recent.map((r) => r.totalMs)),
    frames: recent.length,
    decoder: state.decoder,
  };
}

// The small panel over the image's corner: the same medians (`s`, when
// the caller has them already).
export function updateStatsPanel(s = pageStats()) {
  $('stats-panel').textContent = [
    `${fixed(s.fps, 0)} frames/s`,
    `decode ${fixed(s.decode_ms, 1)} ms (${s.decoder})`,
    `segment ${fixed(s.segment_ms, 2)} ms`,
    `cloud ${fixed(s.cloud_ms, 2)} ms`,
    `track ${fixed(s.track_ms, 2)} ms`,
    `frame ${fixed(s.total_ms, 2)} ms`,
  ].join('\n');
  $('stats-panel').title = `Medians over the last ${s.frames} frames; "frame" is segmentation + cloud + tracking`;
}

// A recovery test that fired on a frame whose state was kept, and why it
// was kept (the record's `checks`); a recovered frame's reason says the rest.
function checksText(r) {
  const c = r && r.record && r.record.checks;
  if (!c || !c.fired.length || c.verdict === 'recovered') return '';
  return `   ${c.fired.join(', ')} fired: ${c.verdict.replace(/_/g, ' ')}`;
}

export function updateLabels(page = pageStats()) {
  const n = state.seq.info.color_files.length;
  $('timeline').value = String(state.index);
  $('frame-label').textContent = `${state.index + 1} / ${n}`;
  const r = state.results[state.index];
  const tracked = state.results.slice(0, state.tracked + 1).filter(Boolean);
  const fps = page.fps;
  const lines = [
    `sequence ${state.seq.name}   frame ${state.index}   status ${r ? r.status : '-'}${r && r.reason ? ` (${r.reason})` : ''}${checksText(r)}`,
    r ? `tracking ${r.trackMs.toFixed(2)} ms   segmentation+cloud+tracking ${r.totalMs.toFixed(2)} ms   decoding ${r.decodeMs.toFixed(1)} ms   median tracking ${fixed(stats(tracked.map((x) => x.trackMs)).median, 2)} ms` : '',
    `display ${fixed(fps, 1)} frames/s   visible nodes ${r ? r.visible.filter((v) => v).length : '-'} of ${r ? r.visible.length : '-'}`,
    r && r.error.length ? `frame error ${r.error[0].toFixed(2)} mm, ${r.error[1].toFixed(2)} px (${ALGORITHM_NAMES[state.params.algorithm]}, red)` : 'no ground truth for this frame',
  ];
  if (r && r.ropes.length) {
    lines.push(`ropes: ${r.ropes.map((x) => `${x.name} ${x.status}${x.error.length ? ` ${x.error[0].toFixed(2)} mm` : ''}`).join('   ')}`);
  }
  const c = r && r.second;
  if (c) {
    const err = c.error.length ? `frame error ${c.error[0].toFixed(2)} mm, ${c.error[1].toFixed(2)} px` : 'no ground truth';
    lines.push(`compared: ${ALGORITHM_NAMES[state.compare]} (cyan): ${err}   tracking ${c.trackMs.toFixed(2)} ms   status ${c.status}   median tracking ${fixed(stats(tracked.filter((x) => x.second).map((x) => x.second.trackMs)).median, 2)} ms`);
  }
  $('stats').textContent = lines.join('\n');
}

export function drawPlot() {
  const c = $('plot');
  const g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  const n = state.seq.info.color_files.length;
  const ropes = state.seq.info.ropes || [];
  const series = ropes.length
    ? ropes.map((rope, k) => ({ name: state.params.algorithm, rope: rope.name, colours: ROPE_COLOURS[k % ROPE_COLOURS.length], of: (r) => r.ropes[k] }))
    : [{ name: state.params.algorithm, colours: MAIN_COLOURS, of: (r) => r }];
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
    const mm = stats(s.errs.map((e) => e[1])).mean;
    const px = stats(s.errs.map((e) => e[2])).mean;
    g.setLineDash([4, 3]); g.beginPath(); g.moveTo(30, y(mm)); g.lineTo(c.width - 10, y(mm)); g.stroke(); g.setLineDash([]);
    const who = s.rope ? `${s.rope} (${ALGORITHM_NAMES[s.name]})` : ALGORITHM_NAMES[s.name];
    labels.push(`${who} mean ${mm.toFixed(2)} mm, ${px.toFixed(2)} px over ${s.errs.length} frames`);
  }
  g.strokeStyle = '#000'; g.beginPath(); g.moveTo(x(state.index), 5); g.lineTo(x(state.index), c.height - 15); g.stroke();
  $('plot-label').textContent = `Frame error (mm) over time (dashed: means). ${labels.join('; ')}.`;
}
