// Finding the rope: what initialisation found on a frame said in the banner
// (several rope-shaped candidates, or none), a click on the rope choosing
// it (with "Pick rope colour", which also takes its colour), and the rope's
// length and diameter when the user knows them (dlo.json's "rope").
import { state, $, showNote, afterBusy } from './state.js';
import { call } from './worker-client.js';
import { Request } from './protocol.js';
import { retrackFromHere } from './playback.js';
import { checkDlo } from './core.js';

// The epoch a note was last shown in: one note per change of settings.
let notedEpoch = -1;

// Tells the user when the rope found on frame k is a choice among several
// rope-shaped candidates (or the click missed them all), or when nothing in
// the colour range is rope-shaped.
export function noteRopeFinding(k, r) {
  if (notedEpoch === state.epoch) return;
  const init = r.init;
  let text = null;
  const missing = (r.ropes || []).filter((x) => x.status === 'lost');
  if (r.ropes && r.ropes.length) {
    // Several ropes: each takes a candidate of its colour the others have
    // not; say which were not found.
    if (missing.length) {
      text = `Frame ${k}: ${missing.map((x) => `${x.name} not found (${(x.reason || '').replace(/^not initialised: /, '')})`).join('; ')}.`;
    }
  } else if (init && ((init.candidates.length > 1 && init.rule !== 'clicked') || init.hint_missed)) {
    const c = init.candidates[init.chosen];
    const how = init.rule === 'clicked' ? 'the one clicked' : init.rule === 'nearest_previous' ? 'the one nearest the rope tracked before' : 'the longest';
    text = `Frame ${k}: ${init.candidates.length} rope-shaped candidates in the colour range; tracking ${how} ` +
      `(${c.length.toFixed(2)} m, ${(c.diameter * 1000).toFixed(1)} mm thick).` +
      (init.hint_missed ? ' The click was on none of them.' : '') +
      ' Not the rope? "Pick rope colour", then click the rope.';
  } else if (r.status === 'lost' && /nothing rope-shaped/.test(r.reason || '')) {
    text = `Frame ${k}: ${r.reason.replace(/^not initialised: /, '')}. "Pick rope colour", then click the rope.`;
  }
  if (text) {
    notedEpoch = state.epoch;
    showNote(text);
  }
}

// The rope through pixel (x, y): the colour range around it (`hsv`, picked
// by the caller) and the candidate through it, from the shown frame on.
export async function chooseRopeAt(x, y, hsv) {
  await afterBusy(async () => {
    await call(Request.hsv(hsv));
    state.hsv = hsv;
    await call(Request.rope([x, y], state.rope));
  });
  return retrackFromHere(true);
}

// The rope's length and diameter as dlo.json writes them, from the inputs
// (empty inputs: unknown); checked by the core.
function ropeFromInputs() {
  const length = $('rope-length').value.trim();
  const diameter = $('rope-diameter').value.trim();
  const rope = {};
  if (length) rope.length_m = Number(length);
  if (diameter) rope.diameter_m = Number(diameter) / 1000;
  if (!length && !diameter) return null;
  return checkDlo(JSON.stringify({ rope })).rope;
}

export function setRopeInputs(rope) {
  $('rope-length').value = rope && rope.length_m ? String(rope.length_m) : '';
  $('rope-diameter').value = rope && rope.diameter_m ? String(+(rope.diameter_m * 1000).toFixed(2)) : '';
}

export function bindRopePanel(guarded) {
  $('rope').onchange = guarded(async () => {
    let rope;
    try {
      rope = ropeFromInputs();
    } catch (err) {
      setRopeInputs(state.rope);
      throw err;
    }
    await afterBusy(async () => {
      await call(Request.rope(null, rope));
      state.rope = rope;
    });
    await retrackFromHere(true);
  });
}
