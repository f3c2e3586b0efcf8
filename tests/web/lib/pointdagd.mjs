// A real pointdagd on loopback for the web and browser tests and the benchmarks (as
// tests/server/daemon_util.cc starts one): a temporary --data-dir, port 0 with --port-file, ready
// once /readyz answers; optionally a write token, the viewer's files (--web-dir) and --workers.
// Also: upload a scan, wait for its job, compute its shadows, and list and fetch every tile of a dataset.
import { spawn } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { setTimeout as sleep } from 'node:timers/promises';
import { config } from './config.mjs';

export class Daemon {
  // binary: POINTDAGD (set by ctest), else build/server/pointdagd. webDir: serve the viewer from it.
  static async start({ binary = config.pointdagd, token = null, webDir = null, workers = null, startSeconds = 120 } = {}) {
    if (!binary || !existsSync(binary)) throw new Error(`pointdagd not found at '${binary}' (build it: scripts/build; ctest sets POINTDAGD)`);
    if (webDir && !existsSync(join(webDir, 'index.html'))) {
      throw new Error(`${webDir}/index.html is missing: build the web target (POINTDAG_WEB_DIR names the folder)`);
    }
    const dir = mkdtempSync(join(tmpdir(), 'pointdagd-'));
    const portFile = join(dir, 'port');
    const args = ['--listen', '127.0.0.1:0', '--data-dir', join(dir, 'var'), '--port-file', portFile];
    if (webDir) args.push('--web-dir', webDir);
    if (workers) args.push('--workers', String(workers));
    // Only the token asked for: one inherited from the caller's shell would refuse the tests' uploads.
    const env = { ...process.env };
    delete env.POINTDAGD_TOKEN;
    delete env.POINTDAGD_READ_TOKEN;
    if (token) env.POINTDAGD_TOKEN = token;
    const daemon = new Daemon(spawn(binary, args, { env, stdio: ['ignore', 'pipe', 'pipe'] }), dir);
    try {
      await daemon.waitReady(portFile, startSeconds);
    } catch (err) {
      await daemon.stop();
      throw err;
    }
    return daemon;
  }

  constructor(proc, dir) {
    this.proc = proc;
    this.dir = dir;
    this.log = '';
    this.exited = null;
    this.url = null;
    for (const stream of [proc.stdout, proc.stderr]) stream.on('data', (d) => { this.log += d; });
    this.done = new Promise((resolve) => proc.on('exit', (code, signal) => {
      this.exited = signal ?? `status ${code}`;
      resolve();
    }));
  }

  // Ready is /readyz answering 200, not just the port file: the daemon binds before it is ready.
  async waitReady(portFile, startSeconds) {
    const deadline = Date.now() + startSeconds * 1000;
    while (Date.now() < deadline) {
      if (this.exited) throw new Error(`pointdagd exited during start (${this.exited}):\n${this.log}`);
      if (!this.url && existsSync(portFile)) {
        const port = readFileSync(portFile, 'utf8').trim();
        if (port) this.url = `http://127.0.0.1:${Number(port)}`;
      }
      if (this.url) {
        try {
          if ((await fetch(`${this.url}/readyz`)).ok) return;
        } catch {
          // not listening yet
        }
      }
      await sleep(25);
    }
    throw new Error(`pointdagd was not ready within ${startSeconds} s:\n${this.log}`);
  }

  // SIGTERM, then SIGKILL if it has not exited after 10 s, so that a hung daemon cannot hang the test.
  async stop() {
    if (!this.exited) {
      this.proc.kill('SIGTERM');
      await Promise.race([this.done, sleep(10_000)]);
      if (!this.exited) this.proc.kill('SIGKILL');
    }
    rmSync(this.dir, { recursive: true, force: true });
  }
}

async function getJson(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`GET ${url}: ${r.status} ${await r.text()}`);
  return r.json();
}

// Uploads the scan and waits for its job; returns the dataset id.
export async function ingest(baseUrl, scanPath, { name = 'scan', token = null, epsg = null, timeoutSeconds = 600 } = {}) {
  const crs = epsg ? `&epsg=${epsg}` : '';
  const posted = await fetch(`${baseUrl}/v1/datasets?name=${encodeURIComponent(name)}${crs}`, {
    method: 'POST',
    body: readFileSync(scanPath),
    headers: token ? { Authorization: `Bearer ${token}` } : {},
  });
  if (posted.status !== 202) throw new Error(`upload of ${scanPath}: ${posted.status} ${await posted.text()}`);
  const location = posted.headers.get('location');
  const deadline = Date.now() + timeoutSeconds * 1000;
  for (;;) {
    const job = await getJson(baseUrl + location);
    if (job.status === 'done') return job.dataset_id;
    if (job.status === 'failed') throw new Error(`ingest of ${scanPath} failed: ${job.error}`);
    if (Date.now() > deadline) throw new Error(`ingest of ${scanPath} not done after ${timeoutSeconds} s (stage ${job.stage})`);
    await sleep(100);
  }
}

// Posts a shadow job for the dataset (PROTOCOL.md §3.2; `light` is the request's JSON body, e.g.
// {direction: [x, y, z]}) and waits for it; returns the dataset's metadata after it.
export async function computeShadows(baseUrl, datasetId, light, { timeoutSeconds = 300 } = {}) {
  const posted = await fetch(`${baseUrl}/v1/datasets/${datasetId}/shadows`, {
    method: 'POST',
    headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify(light),
  });
  if (posted.status !== 202) throw new Error(`shadow job for ${datasetId}: ${posted.status} ${await posted.text()}`);
  const location = posted.headers.get('location');
  const deadline = Date.now() + timeoutSeconds * 1000;
  for (;;) {
    const job = await getJson(baseUrl + location);
    if (job.status === 'done') return getJson(`${baseUrl}/v1/datasets/${datasetId}`);
    if (job.status === 'failed') throw new Error(`shadow job for ${datasetId} failed: ${job.error}`);
    if (Date.now() > deadline) throw new Error(`shadow job for ${datasetId} not done after ${timeoutSeconds} s (stage ${job.stage})`);
    await sleep(100);
  }
}

// Every tile of the dataset as {level, x, y, z, voxels}, walking the hierarchy pages.
export async function listTiles(baseUrl, datasetId) {
  const tiles = [];
  const pages = [{ level: 0, x: 0, y: 0, z: 0 }];
  while (pages.length) {
    const p = pages.shift();
    const page = await getJson(`${baseUrl}/v1/datasets/${datasetId}/hierarchy/${p.level}/${p.x}/${p.y}/${p.z}?depth=8`);
    // A page repeats its own node, which the page above listed already.
    for (const t of page.tiles) if (!(p.level > 0 && t.level === p.level)) tiles.push(t);
    pages.push(...page.pages);
  }
  return tiles;
}

export async function fetchTile(baseUrl, datasetId, t) {
  const url = `${baseUrl}/v1/datasets/${datasetId}/tiles/${t.level}/${t.x}/${t.y}/${t.z}`;
  const r = await fetch(url);
  if (!r.ok) throw new Error(`GET ${url}: ${r.status}`);
  return new Uint8Array(await r.arrayBuffer());
}
