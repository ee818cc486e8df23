// Benchmark (not a test): the page in headless Chromium. Prints a table per
// sequence and colour decoder: first frame drawn after navigation (warm
// cache), and playback with tracking at the page's fastest speed (4x, so the
// pacing allows up to 4 x the sequence's fps): frames per second and medians
// of the worker's per-frame times.
//
//   node tests/browser/bench_page.mjs [<sequence folder>...]
//
// Without arguments: the page's default sample. A folder is opened as the
// "Open folder…" button does (make a 1280x720 one with
// `upetrack synth static-s DIR --frames 150 --hd`).
import { serveRepository, launchChromium } from './harness.mjs';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const folders = process.argv.slice(2);

// Cached for an hour, as a static host would: the second visit is warm.
const { server, origin } = await serveRepository(root, { cache: true });
const context = await launchChromium(fs.mkdtempSync(path.join(os.tmpdir(), 'upetrack-bench-')));

const med = (xs) => [...xs].sort((a, b) => a - b)[xs.length >> 1];

// Plays the open sequence to its end at 4x and returns the measurements.
async function playback(page) {
  return page.evaluate(async () => {
    const u = window.upetrack;
    const n = u.state.seq.info.color_files.length;
    const t0 = performance.now();
    document.getElementById('play').click();
    while (u.state.index < n - 1 || u.state.playing) await new Promise((res) => setTimeout(res, 2));
    const ms = (performance.now() - t0) / (n - 1);
    return { frames: n, perFrame: ms, stats: u.stats, w: u.state.frame.width, h: u.state.frame.height, fps: u.state.seq.info.fps, seq: u.state.seq.name };
  });
}

const rows = [];
for (const decoder of (process.env.DECODERS || 'browser,canvas,wasm').split(',')) {
  const query = `?autoplay=0&speed=4&decode=${decoder}`;
  const page = await context.newPage();
  if (!folders.length) {
    // Once to fill the cache, then the measured visit.
    await page.goto(`${origin}/web/index.html${query}`);
    await page.evaluate(() => window.upetrack.ready);
    await page.goto(`${origin}/web/index.html${query}`);
    await page.waitForFunction(() => window.upetrack && window.upetrack.state.frame, null, { timeout: 60000 });
    const first = await page.evaluate(() => window.upetrack.state.shownAt[0]);
    const r = await playback(page);
    rows.push({ decoder, first, ...r, name: `${r.seq} (bundled, the page's default)` });
  }
  for (const dir of folders) {
    await page.goto(`${origin}/web/index.html${query}`);
    await page.evaluate(() => window.upetrack.ready);
    await page.setInputFiles('#folder', dir);
    await page.waitForFunction((name) => window.upetrack.state.seq && window.upetrack.state.seq.name === name && window.upetrack.state.frame, path.basename(dir), { timeout: 120000 });
    const r = await playback(page);
    rows.push({ name: path.basename(dir), decoder, first: NaN, ...r });
  }
  await page.close();
}
console.log('| sequence | size | colour decoded by | first frame after navigation (warm) | playback at 4x | median decode | median segmentation + cloud + tracking | median tracking step |');
console.log('|---|---|---|---:|---:|---:|---:|---:|');
for (const r of rows) {
  const s = r.stats;
  console.log(`| ${r.name} (${r.frames} frames) | ${r.w}x${r.h} | ${r.decoder} | ${Number.isFinite(r.first) ? `${r.first.toFixed(0)} ms` : '-'} | ${(1000 / r.perFrame).toFixed(1)} fps (cap ${4 * r.fps}) | ${s.decode_ms.toFixed(1)} ms | ${s.total_ms.toFixed(2)} ms | ${s.track_ms.toFixed(2)} ms |`);
}
await context.close();
server.close();
