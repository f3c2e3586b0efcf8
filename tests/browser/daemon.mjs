// A real pointdagd for the browser tests: a temporary --data-dir, a free loopback port, the viewer's
// static files (--web-dir) and optionally a write token. Paths come from the environment that
// tests/browser/CMakeLists.txt sets: POINTDAG_DAEMON (the binary) and POINTDAG_WEB_DIR (build.mjs's output).
import { spawn } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { setTimeout as sleep } from 'node:timers/promises';

const START_TIMEOUT_MS = 30_000;

function requiredPath(name, what) {
  const value = process.env[name];
  if (!value) throw new Error(`${name} is not set: it names ${what} (ctest sets it; see tests/browser/CMakeLists.txt)`);
  if (!existsSync(value)) throw new Error(`${name}=${value} does not exist: build the project first (scripts/build)`);
  return value;
}

export class Daemon {
  // Starts the daemon and waits until /readyz answers 200.
  static async start({ token = null } = {}) {
    const binary = requiredPath('POINTDAG_DAEMON', 'the pointdagd binary');
    const webDir = requiredPath('POINTDAG_WEB_DIR', 'the viewer built by web/build.mjs');
    if (!existsSync(join(webDir, 'index.html'))) throw new Error(`${webDir}/index.html is missing: build the web target`);
    const daemon = new Daemon(mkdtempSync(join(tmpdir(), 'pointdag-browser-')));
    const env = { ...process.env };
    delete env.POINTDAGD_TOKEN;
    delete env.POINTDAGD_READ_TOKEN;
    if (token) env.POINTDAGD_TOKEN = token;
    daemon.process = spawn(binary, [
      '--data-dir', join(daemon.dir, 'data'), '--listen', '127.0.0.1:0',
      '--port-file', daemon.portFile, '--web-dir', webDir, '--workers', '1',
    ], { env, stdio: ['ignore', 'pipe', 'pipe'] });
    daemon.process.stdout.on('data', (d) => { daemon.log += d; });
    daemon.process.stderr.on('data', (d) => { daemon.log += d; });
    daemon.process.on('exit', (code, signal) => { daemon.exited = { code, signal }; });
    try {
      await daemon.waitReady();
    } catch (err) {
      await daemon.stop();
      throw err;
    }
    return daemon;
  }

  constructor(dir) {
    this.dir = dir;
    this.portFile = join(dir, 'port');
    this.log = '';
    this.exited = null;
    this.url = null;
  }

  async waitReady() {
    const deadline = Date.now() + START_TIMEOUT_MS;
    while (Date.now() < deadline) {
      if (this.exited) throw new Error(`pointdagd exited (${JSON.stringify(this.exited)}) before it was ready:\n${this.log}`);
      if (!this.url && existsSync(this.portFile)) {
        const port = readFileSync(this.portFile, 'utf8').trim();
        if (port) this.url = `http://127.0.0.1:${port}`;
      }
      if (this.url) {
        try {
          if ((await fetch(`${this.url}/readyz`)).ok) return;
        } catch {
          // not listening yet
        }
      }
      await sleep(50);
    }
    throw new Error(`pointdagd was not ready after ${START_TIMEOUT_MS} ms:\n${this.log}`);
  }

  async stop() {
    if (this.process && !this.exited) {
      const exited = new Promise((resolve) => this.process.once('exit', resolve));
      this.process.kill('SIGTERM');
      await Promise.race([exited, sleep(10_000)]);
      if (!this.exited) this.process.kill('SIGKILL');
    }
    rmSync(this.dir, { recursive: true, force: true });
  }
}
