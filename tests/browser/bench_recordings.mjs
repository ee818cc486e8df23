// Benchmark (not a test): a large recording on the page in headless
// Chromium. Prints a table: time from picking the file to the first frame
// drawn, and playback with tracking (frames per second, medians of the
// worker's per-frame decode and tracking times), at the page's fastest speed (4x).
//
//   node tests/browser/bench_recordings.mjs <recording> [frames]
//
// Make large recordings with scripts/bench_recordings.py.
import { serveRepository, launchChromium } from './harness.mjs';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const [recording, framesArg] = process.argv.slice(2);
if (!recording) { console.error('usage: node bench_recordings.mjs <recording> [frames]'); process.exit(2); }
const frames = Number(framesArg || 150);

const { server, origin } = await serveRepository(root);
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'upetrack-bench-'));
const context = await launchChromium(tmp);
const page = await context.newPage();
await page.goto(`${origin}/web/index.html?autoplay=0&speed=4`);
await page.evaluate(() => window.upetrack.ready);
await page.evaluate(() => { window.__t0 = performance.now(); });
await page.setInputFiles('#recording', recording);
await page.waitForFunction(() => window.upetrack.state.seq && window.upetrack.state.seq.fromRecording && window.upetrack.state.frame, null, { timeout: 120000 });
const first = await page.evaluate(() => performance.now() - window.__t0);
const r = await page.evaluate(async (n) => {
  const u = window.upetrack;
  const last = Math.min(n, u.state.seq.info.color_files.length) - 1;
  const t0 = performance.now();
  document.getElementById('play').click();
  while (u.state.index < last && u.state.playing) await new Promise((res) => setTimeout(res, 2));
  const ms = (performance.now() - t0) / last;
  u.state.playing = false;
  const res = u.state.results.slice(1, last + 1);
  const med = (xs) => [...xs].sort((a, b) => a - b)[xs.length >> 1];
  return { frames: last, perFrame: ms, decode: med(res.map((x) => x.decodeMs)), track: med(res.map((x) => x.trackMs)), total: med(res.map((x) => x.totalMs)), w: u.state.frame.width, h: u.state.frame.height };
}, frames);
const size = fs.statSync(recording).size;
console.log(`| recording | size | first frame | playback (${r.frames} frames, ${r.w}x${r.h}) | median read+decode+align | median segmentation+cloud+tracking | median tracking step |`);
console.log('|---|---:|---:|---:|---:|---:|---:|');
console.log(`| ${path.basename(recording)} | ${(size / 1e9).toFixed(2)} GB | ${(first / 1000).toFixed(2)} s | ${(1000 / r.perFrame).toFixed(1)} fps (${r.perFrame.toFixed(1)} ms a frame) | ${r.decode.toFixed(1)} ms | ${r.total.toFixed(2)} ms | ${r.track.toFixed(2)} ms |`);
await context.close();
server.close();
fs.rmSync(tmp, { recursive: true, force: true });
