// The page's side of the worker: one request, one promise.
import { showError, progress } from './state.js';

const worker = new Worker('./worker.js', { type: 'module' });
const pending = new Map();
let nextId = 1;
worker.onmessage = (e) => {
  const p = pending.get(e.data.id);
  if (!p) return;
  if (e.data.progress) { progress(e.data.progress[0], e.data.progress[1]); return; }
  pending.delete(e.data.id);
  if (e.data.ok) p.resolve(e.data); else p.reject(new Error(e.data.error));
};
worker.onerror = (e) => showError(`Worker failed: ${e.message}`);

// Sends a request made by protocol.js's `Request`; resolves with the reply.
export function call(request, transfer = []) {
  return new Promise((resolve, reject) => {
    const id = nextId++;
    pending.set(id, { resolve, reject });
    worker.postMessage({ ...request, id }, transfer);
  });
}
