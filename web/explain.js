// The explain mode: one frame's update shown stage by stage over the image,
// each with a short text and the paper's equations: the segmented pixels,
// the point cloud, the visibility test, every EM iteration with its
// responsibilities, the occlusion estimate's sweeps, and the resampling.
// The worker explains the frame from the tracker's state before it (the
// core's Tracker::explain: the frame's own update, stage by stage).
import { state, $ } from './state.js';
import { call } from './worker-client.js';
import { Request } from './protocol.js';
import { frameFields, activeRects } from './sequence.js';
import { canvas, ctx, MAIN_COLOURS } from './draw.js';

const fmt = (x, d = 1) => (Number.isFinite(x) ? x.toFixed(d) : '-');
const COLOURS = { cloud: '#00e0ff', visible: '#30d050', hidden: '#ffa000', forward: '#00c8ff', backward: '#ff4fd8', slid: '#ffe000', line: '255,255,255', displacement: '#7dff5a' };

// Displacements of a frame are a few pixels: drawn this many times longer.
const DISPLACEMENT_SCALE = 5;

// The known nodes next to each hidden run (its anchors) and the three known
// nodes on each side whose displacements Eq. 6 uses.
function anchorsAndNeighbours(visible) {
  const n = visible.length;
  const anchors = new Set();
  const neighbours = new Set();
  for (let m = 0; m < n; m++) {
    if (visible[m]) continue;
    for (const dir of [-1, 1]) {
      const a = m + dir;
      if (a < 0 || a >= n || !visible[a]) continue;
      anchors.add(a);
      for (let k = 0; k < 3; k++) {
        const j = a + dir * k;
        if (j >= 0 && j < n && visible[j]) neighbours.add(j);
      }
    }
  }
  return { anchors: [...anchors], neighbours: [...neighbours] };
}

// The steps of a frame's explanation, each { name, title, text, draw }.
function steps(v) {
  const p = state.params;
  const mm = (m) => fmt(m * 1000, 1);
  const out = [
    {
      name: 'segmentation', title: 'Segmentation',
      text: `${v.mask_pixels} pixels have a colour inside the HSV range (H ${state.hsv.lower[0]}-${state.hsv.upper[0]}, S ${state.hsv.lower[1]}-${state.hsv.upper[1]}, V ${state.hsv.lower[2]}-${state.hsv.upper[2]}, OpenCV's 8-bit HSV${state.hsv.chroma_noise ? `; saturation within ${state.hsv.chroma_noise} levels of colour noise` : ''}). Occlusion rectangles are blacked out first, so nothing under them is seen (Sec. III-A).`,
      draw: drawMask,
    },
    {
      name: 'cloud', title: 'Point cloud X^t',
      text: `${v.deprojected_points} of them have a valid depth and are deprojected to 3D; ${p.downsampling === 'voxel_grid' || (p.downsampling === 'auto' && p.algorithm !== 'upetrack') ? `a ${mm(p.voxel_size)} mm voxel grid keeps one centroid per cube` : `columns along the viewing rays, ${mm(p.voxel_size / 2)} mm wide, split where the depth jumps, keep one centroid each (the mean depth of their pixels, which a voxel grid would push deeper)`}: ${v.cloud_px.length / 2} points, each pushed π/4 of the rope's radius away from the camera, from the rope's surface to its axis.`,
      draw: () => { dim(); dots(v.cloud_px, COLOURS.cloud, 2); },
    },
  ];
  if (!v.previous_px.length) {
    out.push({
      name: 'initialisation', title: 'Initialisation',
      text: `There is no previous state (status: ${v.status}): the nodes are laid along the centre line of the rope-shaped candidate taken (the one clicked, the one nearest the last state, or the longest; with several, the message above the image says which and why), ${v.output_px.length / 2} nodes at equal spacing${p.node_spacing_diameters > 0 ? `: as many as put them ${fmt(p.node_spacing_diameters, 1)} of the rope's diameters apart, at least M = ${p.node_count} and at most 48 (this project's addition; kept for the sequence)` : ''}.`,
      draw: () => { dim(); dots(v.cloud_px, COLOURS.cloud, 1.5); nodes(v.output_px, MAIN_COLOURS.visible); },
    });
    return out;
  }
  const seen = v.visible.filter(Boolean).length;
  out.push({
    name: 'visibility', title: 'Visibility (Fig. 3)',
    text: `A node of the previous frame is visible when at least V_lim = ${v.visibility_min_points} cloud points lie within r_vis = ${mm(p.visibility_radius)} mm of it (circles; the number is q), and at least ${fmt(p.visibility_min_fraction, 2)} of the visible nodes' median q (this project's addition; 0 gives the paper's rule).${p.hidden_under_crossings ? ' Where the rope crosses itself, a node under the other stretch counts as hidden and explains its points without moving; the stretch on top is the one whose rope pixels read nearer beside the crossing (this project\'s addition).' : ''} ${seen} of ${v.visible.length} are visible (green), ${v.visible.length - seen} hidden (orange).`,
    draw: () => {
      dim();
      dots(v.cloud_px, COLOURS.cloud, 1.5);
      for (let m = 0; m < v.visible.length; m++) {
        const [u, w] = [v.previous_px[2 * m], v.previous_px[2 * m + 1]];
        const colour = v.visible[m] ? COLOURS.visible : COLOURS.hidden;
        ctx.strokeStyle = colour; ctx.lineWidth = 1.5;
        ctx.beginPath(); ctx.arc(u, w, v.radius_px[m], 0, 2 * Math.PI); ctx.stroke();
        ctx.fillStyle = colour; ctx.beginPath(); ctx.arc(u, w, 3, 0, 2 * Math.PI); ctx.fill();
        label(String(v.counts[m]), u + 5, w - 5, colour);
      }
    },
  });
  if (!v.checks) {
    out.push(noStep(v, p));
    return out;
  }
  v.em.forEach((it, k) => {
    const next = k + 1 < v.em.length ? v.em[k + 1].nodes_px : v.registered_px;
    out.push({
      name: `em-${k + 1}`, title: `EM iteration ${k + 1} of ${v.em.length} (Eq. 1-5)`,
      text: `E-step (Eq. 4): each point is shared among the visible nodes by its posterior P(m|x), drawn as lines (brighter: larger; below ${0.05} not drawn), with a uniform outlier term of weight w = ${fmt(p.outlier_weight, 2)} (μ in Eq. 4). M-step (Eq. 5): each visible node moves to the weighted mean of its points (small dots: where it goes), and σ² is re-estimated: σ² = ${fmt(it.variance_mm2, 2)} mm² in this iteration. Hidden nodes take no part${p.hidden_nodes_absorb ? ', except those hidden by the median test alone (q ≥ V_lim): they keep their own points without moving (this project\'s addition)' : ''}.`,
      draw: () => {
        dim();
        for (let j = 0; j < it.line_point.length; j++) {
          const i = it.line_point[j], m = it.line_node[j];
          ctx.strokeStyle = `rgba(${COLOURS.line},${Math.min(1, 0.15 + it.line_p[j]).toFixed(2)})`;
          ctx.lineWidth = 1;
          ctx.beginPath(); ctx.moveTo(v.cloud_px[2 * i], v.cloud_px[2 * i + 1]); ctx.lineTo(it.nodes_px[2 * m], it.nodes_px[2 * m + 1]); ctx.stroke();
        }
        dots(v.cloud_px, COLOURS.cloud, 1.5);
        nodes(it.nodes_px, MAIN_COLOURS.visible, v.visible);
        dots(next, '#ffffff', 1.5);
      },
    });
  });
  const hidden = v.visible.length - seen;
  const ends = v.end_runs.filter(Boolean).length;
  out.push({
    name: 'upe', title: 'Occlusion estimate: UPE (Eq. 6-11)',
    text: hidden
      ? `Each hidden node (hollow: where it was) is placed from the three known nodes before it in the sweep's direction, from the run's anchor (white ring) on: their displacements since the last frame (green arrows, ${DISPLACEMENT_SCALE} times longer) decayed by γ = ${fmt(p.displacement_decay, 2)} (Eq. 6-7) give one estimate, the last two known nodes extended by b = ${fmt(p.bending_resistance, 2)} times the old spacing with a = ${fmt(p.curvature_retention, 2)} of the old bend (Eq. 8-10) another; α = ${fmt(p.displacement_weight, 2)} blends them (Eq. 11). The sweep forward (cyan) and backward (magenta) both reach a run in the middle, which takes their mean; ${ends ? `${ends} node${ends > 1 ? 's' : ''} of a run at an end of the rope use α_end = ${fmt(p.end_displacement_weight, 2)}${p.hidden_motion !== 'paper' ? ' and slide along the rope (yellow)' : ''}` : 'no run reaches an end of the rope'}. Orange: the result.`
      : 'Every node is visible in this frame: there is nothing to estimate.',
    draw: () => {
      dim();
      dots(v.cloud_px, COLOURS.cloud, 1);
      polyline(v.estimated_px, 'rgba(255,255,255,0.6)');
      // Each run's anchors (the known nodes next to it, white rings) and
      // the displacements D_k of the three known nodes on each side since
      // the last frame (green, drawn 5 times longer).
      const { anchors, neighbours } = anchorsAndNeighbours(v.visible);
      for (const m of neighbours) {
        const [u0, w0] = [v.previous_px[2 * m], v.previous_px[2 * m + 1]];
        const [du, dw] = [v.registered_px[2 * m] - u0, v.registered_px[2 * m + 1] - w0];
        arrow(u0, w0, u0 + DISPLACEMENT_SCALE * du, w0 + DISPLACEMENT_SCALE * dw, COLOURS.displacement);
      }
      for (const m of anchors) {
        ctx.strokeStyle = '#ffffff'; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.arc(v.registered_px[2 * m], v.registered_px[2 * m + 1], 7, 0, 2 * Math.PI); ctx.stroke();
      }
      for (let m = 0; m < v.visible.length; m++) {
        if (v.visible[m]) continue;
        const [u0, w0] = [v.previous_px[2 * m], v.previous_px[2 * m + 1]];
        const [u1, w1] = [v.estimated_px[2 * m], v.estimated_px[2 * m + 1]];
        ctx.strokeStyle = COLOURS.hidden; ctx.lineWidth = 1.5;
        ctx.beginPath(); ctx.arc(u0, w0, 4, 0, 2 * Math.PI); ctx.stroke();
        arrow(u0, w0, u1, w1, COLOURS.hidden);
        for (const [arr, colour] of [[v.forward_px, COLOURS.forward], [v.backward_px, COLOURS.backward], [v.slid_px, COLOURS.slid]]) {
          if (Number.isFinite(arr[2 * m])) { ctx.fillStyle = colour; ctx.fillRect(arr[2 * m] - 2, arr[2 * m + 1] - 2, 4, 4); }
        }
      }
      nodes(v.estimated_px, MAIN_COLOURS.visible, v.visible, COLOURS.hidden);
    },
  });
  out.push({
    name: 'resampling', title: 'Resampling (Eq. 12-15)',
    text: `The nodes are moved along the polyline they form to equal geodesic spacing l = L/(M−1) (Eq. 12-15): L = ${fmt(v.length_before_mm, 1)} mm before (thin line), ${fmt(v.length_after_mm, 1)} mm after.${p.conserve_length ? ' Before that, a rope longer than its rest length had its hidden runs shortened: a run at an end to its share, a run between two visible stretches by the excess beyond half a node spacing or, where one stretch was seen pulled away from it, by the rope that slid out of it on this frame, straightening from the pulled side (this project\'s addition: a rope pulled round a hidden bend tightens it).' : ''}${p.extend_short_ends ? ` A rope found shorter than its rest length (the length at initialisation less its rounded tips) first had its visible ends extended along their tangents, over rope pixels${p.extend_under_occluders ? ', under whatever hides the rope at the pixel' : ''} or out of the image, by what it lacked (this project\'s addition: EM draws the end nodes in).` : ''}${p.keep_end_run_spacing ? ' A hidden run at an end of the rope keeps the rest spacing along its own curve; only the part between the hidden ends is spread evenly, so length lost where nothing shows the rope is not taken from the hidden runs (this project\'s addition).' : ''}${p.follow_emerged_ends ? ' Before that, a hidden end whose rope came out from under its occluder into view (rope no node explains, next to what hides the rope at one tip only, within the end\'s length) is laid onto it, the rest of its length pulled straight to where it comes out; and a rope found shorter than its rest length went on past an end along rope in view no node explains, as far as what it lacked reaches, its nodes spread over it (this project\'s additions: EM leaves a fast-pulled end behind).' : ''}${(p.report_on_arcs || p.report_seen_tips) ? ` These are the frame\'s state; its reported nodes are the same${p.report_on_arcs ? ' with each visible node on a bend moved out by the depth of the centroid of the arc of rope it explains, where EM put it' : ''}${p.report_on_arcs && p.report_seen_tips ? ', and' : ''}${p.report_seen_tips ? ' with each end node in view carried along its tangent to the rope\'s tip, where the mask ends less the rope\'s radius (EM leaves an end node inside the tip)' : ''} (this project\'s additions; the next frame starts from the state).` : ' These are the frame\'s nodes.'}`,
    draw: () => {
      dim();
      polyline(v.before_resampling_px, 'rgba(255,255,255,0.5)');
      dots(v.before_resampling_px, '#ffffff', 2);
      polyline(v.resampled_px, MAIN_COLOURS.line);
      nodes(v.resampled_px, MAIN_COLOURS.visible, v.visible, MAIN_COLOURS.hidden);
    },
  });
  out.push(checksStep(v));
  return out;
}

// What each verdict of the recovery tests means (the result file's
// `checks.verdict`).
function verdictText(c) {
  const f = c.found;
  const found = f ? `the rope found (${fmt(f.length * 100, 0)} cm long${f.diameter ? `, ${fmt(f.diameter * 1000, 1)} mm thick` : ''})` : 'the rope found';
  switch (c.verdict) {
    case 'agreed': return 'the state agrees with the images and is kept.';
    case 'waited': return 'recoveries in a row back off, so the state is kept on this frame without looking.';
    case 'nothing_found': return 'the images were searched and hold no rope: the state is kept.';
    case 'other_thickness': return `${found} is not as thick as the rope tracked (another rope-coloured thing): the state is kept.`;
    case 'beside_the_rope': return `only the unexplained share fired and ${found} is the rope tracked: what was left unexplained lies beside the rope, and is remembered as not rope.`;
    case 'leaves_seen_rope_out': return `${found} leaves out ${f ? f.seen_left_out : 'some'} nodes the state sees on rope: it is something else, or only part of the rope, and the state is kept.`;
    case 'recovered': return `${found} replaced the state (white): the frame is reported as recovered.`;
    default: return c.verdict.replace(/_/g, ' ');
  }
}

// The recovery tests after the step (this project's addition).
function checksStep(v) {
  const c = v.checks, l = v.limits;
  const pct = (x) => `${fmt(100 * x, 0)} %`;
  const fired = (name) => (c.fired.includes(name) ? '; it fired' : '');
  const stretch = c.stretch == null ? 'no rest length is known' : `the rope is ${pct(c.stretch)} of its rest length (above ${pct(l.stretch)} it is stretched)${fired('stretched')}`;
  const freeSpace = `${c.left_in_free_space} of the ${c.hidden_in_free_space} hidden nodes found where the images show the table, not rope, stayed there after the correction (at least ${l.nodes_in_free_space} and most of them contradict)${fired('free_space')}`;
  const unexplained = `${pct(c.unexplained)} of the ${c.cloud_points} cloud points lie farther than ${fmt(l.unexplained_reach_mm, 0)} mm from the nodes' axis (above ${pct(l.unexplained)} the nodes miss rope in view)${fired('unexplained')}`;
  const recovered = c.verdict === 'recovered';
  return {
    name: 'checks', title: 'Recovery tests',
    text: `After the step, three tests read the state against the images (this project's addition: a state the images contradict is replaced by the rope found again). Stretch: ${stretch}. Free space: ${freeSpace}. Unexplained: ${unexplained}. ${c.fired.length ? `Fired: ${c.fired.map((x) => x.replace(/_/g, ' ')).join(', ')}; ` : 'None fired: '}${verdictText(c)}`,
    draw: () => {
      dim();
      dots(v.cloud_px, COLOURS.cloud, 1.5);
      if (recovered) {
        polyline(v.resampled_px, 'rgba(255,255,255,0.35)');
        polyline(v.output_px, MAIN_COLOURS.line);
        dots(v.output_px, '#ffffff', 3);
      } else {
        polyline(v.output_px, MAIN_COLOURS.line);
        nodes(v.output_px, MAIN_COLOURS.visible, v.visible, MAIN_COLOURS.hidden);
      }
    },
  };
}

// A frame on which no step ran: the state was replaced or dropped after
// the visibility test.
function noStep(v, p) {
  const seen = v.visible.filter(Boolean).length;
  const text = {
    recovered: `Only ${seen} of ${v.visible.length} nodes are visible, fewer than ${fmt(100 * p.reinit_visible_fraction, 0)} % of them: the rope may have jumped. The images were searched for the whole rope, and the one found replaced the state (white) before any step.`,
    initialised: `No node is visible: the state was dropped and the rope found again in this frame (white).`,
    lost: `No node is visible and no rope was found in the images: the rope is lost, and is looked for again on the next frames.`,
  }[v.status] || `No step ran on this frame (status: ${v.status}).`;
  return {
    name: 'no-step', title: 'No step: the state replaced or dropped',
    text,
    draw: () => {
      dim();
      dots(v.cloud_px, COLOURS.cloud, 1.5);
      polyline(v.previous_px, 'rgba(255,255,255,0.35)');
      if (v.status !== 'lost') { polyline(v.output_px, MAIN_COLOURS.line); dots(v.output_px, '#ffffff', 3); }
    },
  };
}

// ---------- drawing ----------
// The frame as the tracker saw it: occlusion rectangles blacked out.
function background() {
  const f = state.explain.frame;
  ctx.putImageData(new ImageData(f.rgba, f.width, f.height), 0, 0);
  ctx.fillStyle = 'rgba(0,0,0,0.85)';
  const r = activeRects(state.explain.index);
  for (let k = 0; k < r.length; k += 4) ctx.fillRect(r[k], r[k + 1], r[k + 2], r[k + 3]);
}
function dim() { background(); ctx.fillStyle = 'rgba(0,0,0,0.45)'; ctx.fillRect(0, 0, canvas.width, canvas.height); }
function drawMask() {
  background();
  const f = state.explain.frame;
  const img = ctx.getImageData(0, 0, f.width, f.height);
  for (let k = 0; k < f.mask.length; k++) if (f.mask[k]) { img.data[4 * k] = 255; img.data[4 * k + 1] >>= 2; img.data[4 * k + 2] >>= 2; }
  ctx.putImageData(img, 0, 0);
}
function dots(px, colour, r) {
  ctx.fillStyle = colour;
  for (let k = 0; k < px.length; k += 2) if (Number.isFinite(px[k])) ctx.fillRect(px[k] - r, px[k + 1] - r, 2 * r, 2 * r);
}
function polyline(px, colour) {
  ctx.strokeStyle = colour; ctx.lineWidth = 2; ctx.beginPath();
  let open = false;
  for (let k = 0; k < px.length; k += 2) {
    if (!Number.isFinite(px[k])) { open = false; continue; }
    if (open) ctx.lineTo(px[k], px[k + 1]); else ctx.moveTo(px[k], px[k + 1]);
    open = true;
  }
  ctx.stroke();
}
function nodes(px, colour, visible = null, hiddenColour = COLOURS.hidden) {
  for (let m = 0; m < px.length / 2; m++) {
    if (!Number.isFinite(px[2 * m])) continue;
    ctx.fillStyle = !visible || visible[m] ? colour : hiddenColour;
    ctx.beginPath(); ctx.arc(px[2 * m], px[2 * m + 1], 4, 0, 2 * Math.PI); ctx.fill();
  }
}
function arrow(x0, y0, x1, y1, colour) {
  if (![x0, y0, x1, y1].every(Number.isFinite)) return;
  ctx.strokeStyle = colour; ctx.lineWidth = 1.5;
  ctx.beginPath(); ctx.moveTo(x0, y0); ctx.lineTo(x1, y1); ctx.stroke();
  const a = Math.atan2(y1 - y0, x1 - x0);
  ctx.beginPath(); ctx.moveTo(x1, y1);
  ctx.lineTo(x1 - 6 * Math.cos(a - 0.4), y1 - 6 * Math.sin(a - 0.4));
  ctx.lineTo(x1 - 6 * Math.cos(a + 0.4), y1 - 6 * Math.sin(a + 0.4));
  ctx.closePath(); ctx.fillStyle = colour; ctx.fill();
}
function label(text, x, y, colour) {
  ctx.font = '10px sans-serif'; ctx.fillStyle = 'rgba(0,0,0,0.6)';
  ctx.fillRect(x - 1, y - 9, ctx.measureText(text).width + 2, 11);
  ctx.fillStyle = colour; ctx.fillText(text, x, y);
}

// ---------- the mode ----------
// Explains frame i (tracking the frames before it first) and shows the step
// named `name` (or the first).
// `strict`: a `name` the frame lacks is an error; otherwise the nearest
// step is taken (the last EM iteration for a later one).
export async function explainFrame(i, name, goTo, strict) {
  const n = state.seq.info.color_files.length;
  if (!(i >= 0 && i < n)) throw new Error(`frame ${i} is not in this sequence (frames 0 to ${n - 1})`);
  await goTo(i);
  const snapshot = i > 0 ? state.results[i - 1].snapshot.main : null;
  const [fields, transfer] = await frameFields(i, false);
  // With several ropes, the one picked beside the steps.
  const ropes = state.seq.info.ropes || [];
  const pick = $('explain-rope');
  pick.hidden = ropes.length < 2;
  if (pick.options.length !== ropes.length) pick.replaceChildren(...ropes.map((x, k) => new Option(x.name, String(k))));
  const rope = ropes.length ? Number(pick.value || 0) : 0;
  const r = await call(Request.explain(fields, snapshot, rope), transfer);
  const list = steps(r.view);
  let at = list.findIndex((s) => s.name === name);
  if (at < 0 && name && strict) throw new Error(`step=${name}: frame ${i} has the steps ${list.map((s) => s.name).join(', ')}`);
  if (at < 0) at = name && name.startsWith('em-') ? list.map((s) => s.name.startsWith('em-')).lastIndexOf(true) : 0;
  at = Math.max(0, at);
  state.explain = {
    index: i, steps: list, at, view: r.view, rope: ropes.length ? ropes[rope].name : null,
    frame: { width: r.width, height: r.height, rgba: new Uint8ClampedArray(r.rgba), mask: new Uint8Array(r.mask) },
  };
  showStep();
}

export function showStep() {
  const e = state.explain;
  if (!e) return;
  const s = e.steps[e.at];
  s.draw();
  $('explain-title').textContent = `Frame ${e.index}${e.rope ? `, ${e.rope}` : ''}, step ${e.at + 1} of ${e.steps.length}: ${s.title}`;
  $('explain-text').textContent = s.text;
  $('explain-back').disabled = e.at === 0;
  $('explain-next').disabled = e.at === e.steps.length - 1;
}

export function moveStep(by) {
  const e = state.explain;
  if (!e) return;
  e.at = Math.max(0, Math.min(e.steps.length - 1, e.at + by));
  showStep();
}

// The step shown, as a link's `step=` value.
export const stepName = () => (state.explain ? state.explain.steps[state.explain.at].name : null);
