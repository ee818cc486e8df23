// The result JSON of the contract (docs/sequence-format.md) for what the
// page tracked, and its download.
import { state } from './state.js';

export function resultJson() {
  return {
    algorithm: state.params.algorithm,
    params: state.params,
    frames: state.results.slice(0, state.tracked + 1).map((r, k) => {
      const f = { frame: k, nodes: [], visible: r.visible.map((v) => v === 1), track_ms: r.trackMs, total_ms: r.totalMs };
      for (let j = 0; j < r.nodes.length; j += 3) f.nodes.push([r.nodes[j], r.nodes[j + 1], r.nodes[j + 2]]);
      if (r.status === 'lost') { f.lost = true; f.reason = r.reason; }
      if (r.status === 'recovered') f.recovered = true;
      if (r.init) f.init = r.init;
      return f;
    }),
  };
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
    segmentation: { hsv_lower: state.hsv.lower, hsv_upper: state.hsv.upper },
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
