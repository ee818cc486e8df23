// What the browser tests and benchmarks share: the repository served on
// loopback as a static host would, and Debian's Chromium launched headless
// with a fresh profile and nothing that reaches other hosts.
import { chromium } from 'playwright-core';
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';

const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.css': 'text/css',
  '.wasm': 'application/wasm', '.json': 'application/json', '.png': 'image/png', '.jpg': 'image/jpeg' };

// Flags of every launch (docs: the developers' guide).
const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];

// Serves `root` on 127.0.0.1 (a folder answers with its index.html);
// `cache` lets the browser keep files for an hour, as a static host would.
// Resolves to { server, origin }.
export async function serveRepository(root, { cache = false } = {}) {
  const server = http.createServer((req, res) => {
    const file = path.join(root, decodeURIComponent(new URL(req.url, 'http://x').pathname));
    if (!file.startsWith(root) || !fs.existsSync(file) || fs.statSync(file).isDirectory()) {
      const index = path.join(file, 'index.html');
      if (file.startsWith(root) && fs.existsSync(index)) { res.writeHead(200, { 'content-type': 'text/html' }); return res.end(fs.readFileSync(index)); }
      res.writeHead(404); return res.end('not found');
    }
    const headers = { 'content-type': TYPES[path.extname(file)] || 'application/octet-stream' };
    if (cache) headers['cache-control'] = 'max-age=3600';
    res.writeHead(200, headers);
    res.end(fs.readFileSync(file));
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return { server, origin: `http://127.0.0.1:${server.address().port}` };
}

// Chromium with the profile `profileDir` (fresh), the shared flags and `args`.
export function launchChromium(profileDir, { args = [], viewport } = {}) {
  return chromium.launchPersistentContext(profileDir, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: [...CHROMIUM_ARGS, ...args],
    ...(viewport ? { viewport } : {}),
  });
}
