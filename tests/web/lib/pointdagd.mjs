// A real pointdagd on loopback for the web tests and benchmarks (as tests/server/daemon_util.cc
// starts one): a temporary --data-dir, port 0 with --port-file, no token (loopback only).
// Also: upload a scan, wait for its job, and list and fetch every tile of a dataset.
import { spawn } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { setTimeout as sleep } from 'node:timers/promises';

export class Daemon {
  static async start(pointdagd, { startSeconds = 120 } = {}) {
    if (!pointdagd || !existsSync(pointdagd)) throw new Error(`pointdagd not found at '${pointdagd}' (build it: scripts/build)`);
    const dir = mkdtempSync(join(tmpdir(), 'pointdag-web-'));
    const portFile = join(dir, 'port');
    const proc = spawn(pointdagd, ['--listen', '127.0.0.1:0', '--data-dir', join(dir, 'var'), '--port-file', portFile],
                       { stdio: ['ignore', 'pipe', 'pipe'] });
    const daemon = new Daemon(proc, dir);
    const deadline = Date.now() + startSeconds * 1000;
    while (!existsSync(portFile) || readFileSync(portFile, 'utf8').trim() === '') {
      if (daemon.exited) throw new Error(`pointdagd exited during start (${daemon.exited}):\n${daemon.log}`);
      if (Date.now() > deadline) {
        await daemon.stop();
        throw new Error(`pointdagd did not start within ${startSeconds} s:\n${daemon.log}`);
      }
      await sleep(25);
    }
    daemon.url = `http://127.0.0.1:${Number(readFileSync(portFile, 'utf8'))}`;
    return daemon;
  }

  constructor(proc, dir) {
    this.proc = proc;
    this.dir = dir;
    this.log = '';
    this.exited = null;
    for (const stream of [proc.stdout, proc.stderr]) stream.on('data', (d) => { this.log += d; });
    this.done = new Promise((resolve) => proc.on('exit', (code, signal) => {
      this.exited = signal ?? `status ${code}`;
      resolve();
    }));
  }

  async stop() {
    if (!this.exited) {
      this.proc.kill('SIGTERM');
      await this.done;
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
export async function ingest(baseUrl, scanPath, { name = 'scan', timeoutSeconds = 600 } = {}) {
  const posted = await fetch(`${baseUrl}/v1/datasets?name=${encodeURIComponent(name)}`, {
    method: 'POST',
    body: readFileSync(scanPath),
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
