// The webcam mode: colour only, live from getUserMedia, tracked in the image
// plane. Each frame is taken as an ImageBitmap and tracked in the worker as
// a frame whose depth is the same everywhere (colourOnlyFrame), so the nodes
// move on a plane: hidden runs are estimated the same way as in 3D. The
// camera is taken to have the D435i's field of view (colourOnlySetup).
import { state, $, showNote, showError, settleLookahead } from './state.js';
import { call } from './worker-client.js';
import { Request } from './protocol.js';
import { checkDlo, colourOnlySetup } from './core.js';
import { draw, canvas } from './draw.js';
import { keep } from './playback.js';
import { updateStatsPanel, STATS_WINDOW } from './plot.js';

// Controls that need kept frames: off while the camera is live.
const RECORDED_ONLY = ['play', 'step', 'step-back', 'timeline', 'explain', 'export'];

function setLive(live) {
  for (const id of RECORDED_ONLY) $(id).disabled = live;
  $('webcam').textContent = live ? 'Stop webcam' : 'Webcam';
}

// The resolution asked of the camera (it may give another).
const WANTED = { width: 640, height: 480 };

export async function startWebcam(onOpened) {
  if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) throw new Error('This browser gives no access to a camera here (a page served over https or from localhost is needed).');
  let stream;
  try {
    stream = await navigator.mediaDevices.getUserMedia({ video: { width: { ideal: WANTED.width }, height: { ideal: WANTED.height } }, audio: false });
  } catch (err) {
    throw new Error(`The camera could not be opened: ${err.message || err.name}`);
  }
  const video = document.createElement('video');
  video.muted = true;
  video.playsInline = true;
  video.srcObject = stream;
  await video.play();
  const { camera, depth_scale: depthScale } = colourOnlySetup(video.videoWidth, video.videoHeight);
  stopWebcam();
  state.generation++;
  state.playing = false;
  await settleLookahead();
  const hsv = checkDlo('{}').hsv;
  state.seq = {
    name: 'webcam', live: true, fromZip: false, fromRecording: false, configured: false,
    info: { camera, depth_scale: depthScale, fps: 30, hsv, occlusions: [], color_files: [], depth_files: [], groundtruth: [] },
  };
  state.sampleName = null;
  $('sample').selectedIndex = -1;
  await call(Request.open(camera, state.seq.info.fps, state.params, hsv, null, state.compare));
  state.hsv = hsv;
  state.results = [];
  state.tracked = -1;
  state.index = 0;
  state.userRects = [];
  state.truthPx = null; // a live camera has no ground truth
  state.webcam = { stream, video, frames: 0, depthScale };
  canvas.width = camera.width;
  canvas.height = camera.height;
  setLive(true);
  onOpened(hsv);
  showNote('Webcam: click the rope to take its colour. Tracking is in the image plane (colour only, depth taken as constant).');
  loop(state.webcam).catch((err) => showError(`Webcam: ${err.message || err}`));
}

export function stopWebcam() {
  const w = state.webcam;
  if (!w) return;
  state.webcam = null;
  for (const t of w.stream.getTracks()) t.stop();
  setLive(false);
}

async function loop(w) {
  while (state.webcam === w) {
    // One tracked frame per camera frame: wait for the next one.
    if (w.video.requestVideoFrameCallback) await new Promise((r) => w.video.requestVideoFrameCallback(r));
    else await new Promise((r) => setTimeout(r, 1000 / 30));
    if (state.webcam !== w) break;
    if (w.video.readyState < 2) continue;
    const bitmap = await createImageBitmap(w.video);
    const rects = state.userRects.flat();
    let r;
    try {
      r = await call(Request.frame({
        index: w.frames, track: true, bitmap, depthScale: w.depthScale, occlusions: rects, groundtruth: null,
        wantMask: $('show-mask').checked, wantDepth: false, decoder: 'wasm',
      }), [bitmap]);
    } catch (err) {
      if (state.webcam === w) stopWebcam();
      throw err;
    }
    if (state.webcam !== w) break;
    state.results.push(keep(r));
    if (state.results.length > STATS_WINDOW) state.results.shift();
    state.index = state.results.length - 1;
    state.tracked = state.index;
    state.frame = { width: r.width, height: r.height, rgba: new Uint8ClampedArray(r.rgba), mask: r.mask ? new Uint8Array(r.mask) : null, depth: null, decodeMs: r.decodeMs };
    draw();
    state.shownAt.push(performance.now());
    if (state.shownAt.length > STATS_WINDOW) state.shownAt.shift();
    updateStatsPanel();
    const res = state.results[state.index];
    $('frame-label').textContent = `live ${w.frames + 1}`;
    $('stats').textContent = `webcam ${r.width}x${r.height}   frame ${w.frames}   status ${res.status}   visible nodes ${res.visible.filter(Boolean).length} of ${res.visible.length}   tracking ${res.trackMs.toFixed(2)} ms`;
    w.frames++;
  }
}
