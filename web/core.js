// The core's rules the page needs on its own thread (projection, HSV,
// statistics, folder roots, checking settings, the result JSON, the
// occluders in force), called through the same
// WebAssembly module the worker tracks with: the JS keeps none of them.
import init, {
  projectPoints, rgbToHsv, hsvRangeAround, errorStats, commonRoot, checkDlo, parseParams, parameterSchema, defaultParams, sceneChoices, colourOnlySetup,
  resultFile, activeOcclusions, inputKind, inputHeadBytes,
} from './pkg/upetrack_wasm.js';

export const ready = init();
export {
  projectPoints, rgbToHsv, hsvRangeAround, errorStats, commonRoot, checkDlo, parseParams, parameterSchema, defaultParams, sceneChoices, colourOnlySetup,
  resultFile, activeOcclusions, inputKind, inputHeadBytes,
};
