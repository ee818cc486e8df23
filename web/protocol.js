// The page <-> worker message protocol, written once and imported by both
// sides. The page sends one of these requests with an `id`; the worker
// answers { id, ok: true, ...reply } or { id, ok: false, error }.
//
// request    fields                                          reply
// defaults   -                                               { params }
// info       name, json {file: bytes}, images [paths]        { info }
// open       camera, fps, params, hsv, rope, compare, ropes  {}
//            (ropes: [{name, hsv, rope}] of several, or [])
// params     params                                          { params } (validated, every field)
// hsv        hsv {lower, upper}                              {}
// addRope    hsv, hint ([u, v] clicked on it)                 { ropes: [{name, hsv, rope, hint}] }
// rope       hint ([u, v] clicked, or null), prior           {}
//            (dlo.json's rope, or null)
// restore    snapshot ({main, second} or null)               {}
// zip        bytes (transferred), name                       { names }
// zipRead    path                                            { bytes }
// recording  file (a File, not copied), name, dlo (text|null)  { info, details }; while the index is
//                                                              read: { id, progress: [offset, length] }
// frame      index, track, color, depth, colorName,          { index, width, height, decodeMs, rgba,
//            depthName, fromZip, fromRecording, depthScale,    [nodes, nodesPx, visible, status, reason, init, segmentMs, cloudMs,
//            occlusions, groundtruth, ropeTruths, wantMask,     trackMs, totalMs, error, second, snapshot, ropes,
//            wantDepth, decoder ('browser' | 'wasm'), or bitmap (a webcam's ImageBitmap, transferred) instead of files
//            (ropes, with several: [{name, nodes, nodesPx, visible, status, reason, record, error}])
//                                                               mask], [depth (RGBA ramp)] }
// explain    the frame's fields (as frame), snapshot (of the      { view (wasm's ExplainView), rgba, width, height }
//            frame before, or null), rope (which, of several)

export const Request = {
  defaults: () => ({ type: 'defaults' }),
  info: (name, json, images) => ({ type: 'info', name, json, images }),
  open: (camera, fps, params, hsv, rope, compare, ropes = []) => ({ type: 'open', camera, fps, params, hsv, rope, compare, ropes }),
  params: (params) => ({ type: 'params', params }),
  hsv: (hsv) => ({ type: 'hsv', hsv }),
  rope: (hint, prior) => ({ type: 'rope', hint, prior }),
  addRope: (hsv, hint) => ({ type: 'addRope', hsv, hint }),
  restore: (snapshot) => ({ type: 'restore', snapshot }),
  zip: (bytes, name) => ({ type: 'zip', bytes, name }),
  zipRead: (path) => ({ type: 'zipRead', path }),
  recording: (file, name, dlo) => ({ type: 'recording', file, name, dlo }),
  explain: (f, snapshot, rope = 0) => ({ ...Request.frame(f), type: 'explain', snapshot, rope }),
  frame: (f) => ({
    type: 'frame', index: f.index, track: f.track, color: f.color, depth: f.depth,
    colorName: f.colorName, depthName: f.depthName, fromZip: f.fromZip,
    fromRecording: f.fromRecording, depthScale: f.depthScale,
    occlusions: f.occlusions, groundtruth: f.groundtruth, ropeTruths: f.ropeTruths || [], wantMask: f.wantMask, wantDepth: f.wantDepth,
    decoder: f.decoder, bitmap: f.bitmap,
  }),
};
