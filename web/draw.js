// Drawing one frame: the colour image (or its mask or depth overlay), the
// occlusion rectangles as the tracker saw them, the ground truth and the
// tracked nodes of each algorithm.
import { state, $ } from './state.js';

export const canvas = $('canvas');
export const ctx = canvas.getContext('2d');

// Node colours: line, visible node, hidden node, error curve.
export const MAIN_COLOURS = { line: '#ffffff', visible: '#e02020', hidden: '#ffd000', curve: '#d02020' };
export const COMPARED_COLOURS = { line: '#b8f4ff', visible: '#00e0ff', hidden: '#ff4fd8', curve: '#0098b8' };
// With several ropes, rope k is drawn in ROPE_COLOURS[k] (the first as MAIN_COLOURS).
export const ROPE_COLOURS = [
  MAIN_COLOURS,
  { line: '#ffffff', visible: '#2060ff', hidden: '#ffd000', curve: '#2040d0' },
  { line: '#ffffff', visible: '#10b040', hidden: '#ffd000', curve: '#108030' },
  { line: '#ffffff', visible: '#c040e0', hidden: '#ffd000', curve: '#9020b0' },
  { line: '#ffffff', visible: '#ff8000', hidden: '#ffd000', curve: '#c06000' },
  { line: '#ffffff', visible: '#00c0c0', hidden: '#ffd000', curve: '#008080' },
  { line: '#ffffff', visible: '#808080', hidden: '#ffd000', curve: '#505050' },
  { line: '#ffffff', visible: '#a06030', hidden: '#ffd000', curve: '#704020' },
];
const TRUTH_COLOUR = '#00d000';
const DRAWN_RECT_COLOUR = '#ffcc00';

function image(f) {
  if ($('show-depth').checked && f.depth) return new ImageData(f.depth, f.width, f.height);
  if ($('show-mask').checked && f.mask) {
    const img = new ImageData(new Uint8ClampedArray(f.rgba), f.width, f.height);
    for (let k = 0; k < f.mask.length; k++) if (f.mask[k]) { img.data[4 * k] = 255; img.data[4 * k + 1] >>= 1; }
    return img;
  }
  return new ImageData(f.rgba, f.width, f.height);
}

// A polyline through flat [u, v, ...] pixels; NaN (not projectable) breaks it.
function polyline(px) {
  ctx.beginPath();
  let open = false;
  for (let k = 0; k < px.length; k += 2) {
    const [u, v] = [px[k], px[k + 1]];
    if (!Number.isFinite(u) || !Number.isFinite(v)) { open = false; continue; }
    if (open) ctx.lineTo(u, v); else ctx.moveTo(u, v);
    open = true;
  }
  ctx.stroke();
}

function drawNodes(res, colours) {
  const p = res.nodesPx;
  if (!p.length) return;
  ctx.strokeStyle = colours.line; ctx.lineWidth = 2;
  polyline(p);
  for (let k = 0; k < p.length / 2; k++) {
    if (!Number.isFinite(p[2 * k]) || !Number.isFinite(p[2 * k + 1])) continue;
    ctx.beginPath(); ctx.arc(p[2 * k], p[2 * k + 1], 4, 0, 2 * Math.PI);
    if (res.visible[k]) { ctx.fillStyle = colours.visible; ctx.fill(); } else { ctx.lineWidth = 2.5; ctx.strokeStyle = colours.hidden; ctx.stroke(); }
  }
}

// Draws the shown frame (state.frame, state.index) with everything over it.
export function draw() {
  const f = state.frame;
  if (!f) return;
  ctx.putImageData(image(f), 0, 0);
  const i = state.index;
  const info = state.seq.info;
  // What the tracker saw: occlusion rectangles blacked out.
  ctx.fillStyle = 'rgba(0,0,0,0.85)';
  for (const o of info.occlusions) if (i >= o.frames[0] && i <= o.frames[1]) ctx.fillRect(...o.rect);
  for (const r of state.userRects) {
    ctx.fillRect(...r);
    ctx.save(); ctx.strokeStyle = DRAWN_RECT_COLOUR; ctx.setLineDash([6, 4]); ctx.strokeRect(...r); ctx.restore();
  }
  if ($('show-truth').checked && state.truthPx) {
    ctx.strokeStyle = TRUTH_COLOUR; ctx.lineWidth = 1.5;
    for (const t of state.truthsPx.length ? state.truthsPx : [state.truthPx]) polyline(t);
  }
  const res = state.results[i];
  if (res && res.second) drawNodes(res.second, COMPARED_COLOURS);
  if (res && res.ropes.length) res.ropes.forEach((r, k) => drawNodes(r, ROPE_COLOURS[k % ROPE_COLOURS.length]));
  else if (res) drawNodes(res, MAIN_COLOURS);
}

// A dashed rectangle being dragged, over the drawn frame.
export function drawDragged(a, b) {
  draw();
  ctx.strokeStyle = DRAWN_RECT_COLOUR; ctx.setLineDash([6, 4]);
  ctx.strokeRect(a[0], a[1], b[0] - a[0], b[1] - a[1]);
  ctx.setLineDash([]);
}
