// The result JSON of the contract (docs/sequence-format.md) for what the
// page tracked, and its download.
import { state } from './state.js';
import { resultFile } from './core.js';

export function resultJson() {
  // Made by the core from the records its tracker produced: the command's format, field for field.
  const kept = state.results.slice(0, state.tracked + 1);
  const missing = kept.findIndex((r) => !r);
  if (missing >= 0 || kept.length < state.tracked + 1) throw new Error(`frame ${missing >= 0 ? missing : kept.length} is not tracked yet: track the sequence again`);
  const records = kept.map((r) => r.record);
  // Several ropes: every rope's records too.
  const ropes = (state.seq.info.ropes || []).map((x, k) => ({ name: x.name, records: kept.map((r) => r.ropes[k].record) }));
  return JSON.parse(resultFile(state.params, records, ropes.length ? ropes : null));
}

// The configuration in force as a dlo.json: the colour range, the
// sequence's occluders and those drawn (for every frame), depth scale,
// frame rate and the rope's length and diameter when given. Saved beside a recording, it is what `upetrack track REC --dlo` reads.
export function dloJson() {
  const info = state.seq.info;
  const last = info.color_files.length - 1;
  return {
    depth_scale: info.depth_scale,
    fps: info.fps,
    segmentation: {
      hsv_lower: state.hsv.lower,
      hsv_upper: state.hsv.upper,
      ...(state.hsv.chroma_noise ? { chroma_noise: state.hsv.chroma_noise } : {}),
    },
    occlusions: [...info.occlusions, ...state.userRects.map((r) => ({ frames: [0, last], rect: r }))],
    ...(state.rope ? { rope: state.rope } : {}),
  };
}

export function download(name, object) {
  const blob = new Blob([JSON.stringify(object)], { type: 'application/json' });
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}
