// The page's settings as a link, and a link's settings applied on opening:
// the sample, the algorithms, the colour decoder, the speed, every
// parameter that differs from its default, and the colour range and drawn
// occlusions where they differ from the sequence's own.
import { state, $ } from './state.js';
import { paramsQuery } from './params-panel.js';

export function shareLink() {
  const q = new URLSearchParams();
  if (state.sampleName && state.seq && state.seq.name === state.sampleName) q.set('sample', state.sampleName);
  if (state.params.algorithm !== 'upetrack') q.set('algorithm', state.params.algorithm);
  if (state.compare) q.set('compare', state.compare);
  if (state.decoder !== 'wasm') q.set('decode', state.decoder);
  if ($('speed').value !== '1') q.set('speed', $('speed').value);
  for (const [k, v] of paramsQuery(state.params)) q.set(k, v);
  const own = state.seq && state.seq.info.hsv;
  if (state.hsv && own && JSON.stringify(state.hsv) !== JSON.stringify(own)) {
    const noise = state.hsv.chroma_noise ? [state.hsv.chroma_noise] : [];
    q.set('hsv', [...state.hsv.lower, ...state.hsv.upper, ...noise].join(','));
  }
  if (state.userRects.length) q.set('rects', state.userRects.map((r) => r.join(',')).join(';'));
  if (state.explain) {
    q.set('explain', 'upe');
    q.set('frame', String(state.explain.index));
    q.set('step', state.explain.steps[state.explain.at].name);
  }
  q.set('autoplay', '0');
  const url = new URL(location.href);
  url.search = q.toString();
  return url.toString();
}

// `count` comma-separated whole numbers, or null.
function wholeNumbers(text, count) {
  const v = text.split(',').map((x) => (x.trim() === '' ? NaN : Number(x)));
  return v.length === count && v.every(Number.isInteger) ? v : null;
}

// `hsv=h,s,v,h,s,v[,noise]` as { lower, upper, chroma_noise }, or an error
// naming the value.
export function parseHsvQuery(text) {
  const v = wholeNumbers(text, 6) || wholeNumbers(text, 7);
  if (!v) throw new Error(`hsv=${text}: give six whole numbers, lower h,s,v then upper h,s,v (and the colour noise, a seventh)`);
  return { lower: v.slice(0, 3), upper: v.slice(3, 6), chroma_noise: v[6] || 0 };
}

// `rects=x,y,w,h;...` as rectangles, or an error naming the value.
export function parseRectsQuery(text) {
  return text.split(';').filter(Boolean).map((r) => {
    const v = wholeNumbers(r, 4);
    if (!v) throw new Error(`rects=${text}: give x,y,w,h whole numbers for each rectangle, separated by ;`);
    return v;
  });
}
