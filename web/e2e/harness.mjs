// End-to-end harness: starts the real `corridor serve` on a free port with a fresh database and
// tokens, launches Debian's Chromium through playwright-core, and talks to the API like a vehicle
// or a sensor would. With CORRIDOR_E2E_DIST set (a built console, e.g. web/dist), the console is
// served from that folder by a small same-origin front that adds the server's CSP and forwards
// /v1 (HTTP and WebSocket) to the server: for testing a console build against a server that does
// not embed it yet.
import { spawn } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, writeFileSync, existsSync, statSync } from 'node:fs';
import http from 'node:http';
import net from 'node:net';
import { tmpdir } from 'node:os';
import { extname, join, resolve, normalize } from 'node:path';
import { chromium } from 'playwright-core';

export const DEV_TOKEN = 'e2e-dev-token-0123456789abcdef01'; // 32 characters
export const VIEWER_TOKEN = 'viewer-token-0123456789';
export const SENSOR_TOKEN = 'sensor-token-0123456789';

export const CSP =
  "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; connect-src 'self'; " +
  "font-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'none'; form-action 'self'";

export function artifactsDir() {
  const dir = process.env.CORRIDOR_E2E_ARTIFACTS || mkdtempSync(join(tmpdir(), 'corridor-e2e-artifacts-'));
  mkdirSync(dir, { recursive: true });
  return dir;
}

/** Spawns `corridor serve` with args; resolves with the child and its URL once it listens. */
function spawnServer(bin, args, timeoutMs) {
  const child = spawn(bin, args, { env: { ...process.env, CORRIDOR_DEV_TOKEN: DEV_TOKEN }, stdio: ['ignore', 'pipe', 'pipe'] });
  const state = { child, output: '' };
  return new Promise((resolvePromise, reject) => {
    const timer = setTimeout(() => reject(new Error(`server did not start in ${timeoutMs} ms:\n${state.output}`)), timeoutMs);
    child.stdout.on('data', (chunk) => {
      state.output = (state.output + chunk.toString()).slice(-20000);
      const m = /listening on (http:\/\/127\.0\.0\.1:(\d+))/.exec(state.output);
      if (m && !state.url) {
        state.url = m[1];
        clearTimeout(timer);
        resolvePromise(state);
      }
    });
    child.stderr.on('data', (c) => (state.output = (state.output + c.toString()).slice(-20000)));
    child.on('exit', (code) => {
      clearTimeout(timer);
      if (!state.url) reject(new Error(`server exited with ${code} before listening:\n${state.output}`));
    });
  });
}

function stopChild(child) {
  if (child.exitCode !== null || child.signalCode !== null) return Promise.resolve();
  return new Promise((r) => {
    const t = setTimeout(() => child.kill('SIGKILL'), 5000);
    child.on('exit', () => {
      clearTimeout(t);
      r();
    });
    child.kill('SIGTERM');
  });
}

/** Starts `corridor serve`; resolves once it prints its address. */
export async function startServer({ map, timeoutMs = 120_000 } = {}) {
  const bin = process.env.CORRIDOR_BIN;
  if (!bin) throw new Error('CORRIDOR_BIN must name the corridor executable');
  const dir = mkdtempSync(join(tmpdir(), 'corridor-e2e-'));
  const config = {
    tokens: [
      { token: VIEWER_TOKEN, name: 'wall', roles: ['viewer'] },
      { token: SENSOR_TOKEN, name: 'sensor', roles: ['sensor', 'viewer'] },
    ],
  };
  writeFileSync(join(dir, 'config.json'), JSON.stringify(config));
  const args = (listen) => {
    const a = ['serve', '--listen', listen, '--db', join(dir, 'e2e.db'), '--config', join(dir, 'config.json')];
    if (map) a.push('--map', map);
    return a;
  };
  let current = await spawnServer(bin, args('127.0.0.1:0'), timeoutMs);
  const url = current.url;
  return {
    url,
    dir,
    log: () => current.output,
    /** Stops the server and starts it again on the same address and database. */
    async restart() {
      await stopChild(current.child);
      current = await spawnServer(bin, args(new URL(url).host), timeoutMs);
    },
    stop: () => stopChild(current.child),
  };
}

const TYPES = { '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.css': 'text/css', '.svg': 'image/svg+xml', '.png': 'image/png', '.json': 'application/json' };

/** Serves a console build from dir with the CSP, forwarding /v1 and /metrics to target. */
export async function startFront(dir, target) {
  const t = new URL(target);
  const root = resolve(dir);
  const server = http.createServer((req, res) => {
    if (req.url.startsWith('/v1/') || req.url === '/v1' || req.url.startsWith('/metrics')) {
      const up = http.request({ host: t.hostname, port: t.port, method: req.method, path: req.url, headers: req.headers }, (r) => {
        res.writeHead(r.statusCode, r.headers);
        r.pipe(res);
      });
      up.on('error', () => {
        res.writeHead(502);
        res.end();
      });
      req.pipe(up);
      return;
    }
    const path = normalize(join(root, decodeURIComponent(req.url.split('?')[0]) === '/' ? 'index.html' : decodeURIComponent(req.url.split('?')[0])));
    if (!path.startsWith(root) || !existsSync(path) || !statSync(path).isFile()) {
      res.writeHead(404, { 'Content-Security-Policy': CSP });
      res.end('not found');
      return;
    }
    res.writeHead(200, { 'Content-Type': TYPES[extname(path)] ?? 'application/octet-stream', 'Content-Security-Policy': CSP, 'Cache-Control': 'no-store' });
    res.end(readFileSync(path));
  });
  server.on('upgrade', (req, socket, head) => {
    const up = net.connect(Number(t.port), t.hostname, () => {
      const lines = [`${req.method} ${req.url} HTTP/1.1`];
      for (let i = 0; i < req.rawHeaders.length; i += 2) lines.push(`${req.rawHeaders[i]}: ${req.rawHeaders[i + 1]}`);
      up.write(lines.join('\r\n') + '\r\n\r\n');
      if (head.length) up.write(head);
      up.pipe(socket);
      socket.pipe(up);
    });
    up.on('error', () => socket.destroy());
    socket.on('error', () => up.destroy());
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return {
    url: `http://127.0.0.1:${server.address().port}`,
    stop: () => new Promise((r) => {
      server.closeAllConnections?.();
      server.close(() => r());
    }),
  };
}

export async function launchBrowser() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: [
      '--headless=new',
      '--no-sandbox',
      '--disable-gpu',
      '--disable-quic',
      '--no-first-run',
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
    ],
  });
}

/** A JSON API call; throws with the server's error on a non-2xx answer unless allowed. */
export async function api(base, method, path, { token = DEV_TOKEN, body, allow = [] } = {}) {
  const res = await fetch(base + path, {
    method,
    headers: { Authorization: `Bearer ${token}`, ...(body !== undefined ? { 'Content-Type': 'application/json' } : {}) },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const text = await res.text();
  const json = text ? JSON.parse(text) : null;
  if (!res.ok && !allow.includes(res.status)) throw new Error(`${method} ${path}: ${res.status} ${text}`);
  return { status: res.status, json };
}

export async function waitFor(what, fn, { timeoutMs = 15_000, intervalMs = 200 } = {}) {
  const deadline = Date.now() + timeoutMs;
  let last;
  for (;;) {
    try {
      last = await fn();
      if (last) return last;
    } catch (e) {
      last = e;
    }
    if (Date.now() > deadline) throw new Error(`timed out waiting for ${what}; last: ${last instanceof Error ? last.message : JSON.stringify(last)}`);
    await new Promise((r) => setTimeout(r, intervalMs));
  }
}

/** Bearing in degrees from a to b ([lon, lat] pairs), clockwise from north. */
export function bearing(a, b) {
  const toRad = (d) => (d * Math.PI) / 180;
  const y = Math.sin(toRad(b[0] - a[0])) * Math.cos(toRad(b[1]));
  const x = Math.cos(toRad(a[1])) * Math.sin(toRad(b[1])) - Math.sin(toRad(a[1])) * Math.cos(toRad(b[1])) * Math.cos(toRad(b[0] - a[0]));
  return ((Math.atan2(y, x) * 180) / Math.PI + 360) % 360;
}

export function metres(a, b) {
  const toRad = (d) => (d * Math.PI) / 180;
  const dLat = toRad(b[1] - a[1]);
  const dLon = toRad(b[0] - a[0]);
  const h = Math.sin(dLat / 2) ** 2 + Math.cos(toRad(a[1])) * Math.cos(toRad(b[1])) * Math.sin(dLon / 2) ** 2;
  return 2 * 6371000 * Math.asin(Math.sqrt(h));
}
