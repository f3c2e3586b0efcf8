// Chromium for the browser tests: Debian's /usr/bin/chromium (POINTDAG_CHROMIUM overrides), driven
// by playwright-core from web/node_modules, headless with software WebGL (SwiftShader), against the
// real pointdagd of tests/web/lib/pointdagd.mjs. Missing pieces fail the tests with what to run;
// they never skip.
import { existsSync } from 'node:fs';
import { createRequire } from 'node:module';
import { config } from '../web/lib/config.mjs';
import { Daemon } from '../web/lib/pointdagd.mjs';

const webPackage = new URL('../../web/package.json', import.meta.url);

export const CHROMIUM_ARGS = [
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--no-first-run', '--disable-quic',
];

// playwright-core and pngjs live in web/node_modules (web/package.json), not beside the tests.
export function requireWebModule(name) {
  try {
    return createRequire(webPackage)(name);
  } catch (err) {
    throw new Error(`${name} is not installed in web/node_modules: run scripts/setup (${err.message})`);
  }
}

// A browser with a fresh profile (playwright makes a temporary --user-data-dir per launch).
export async function launchChromium() {
  const executablePath = process.env.POINTDAG_CHROMIUM || '/usr/bin/chromium';
  if (!existsSync(executablePath)) {
    throw new Error(`Chromium is missing (${executablePath}): run scripts/setup, which installs Debian's chromium package`);
  }
  const { chromium } = requireWebModule('playwright-core');
  return chromium.launch({ executablePath, headless: true, args: CHROMIUM_ARGS });
}

// A page of a fixed size at device scale 1 (screenshot pixels = CSS pixels) that records the
// page's errors, so that a failing test can print them.
export async function newPage(browser) {
  const context = await browser.newContext({ viewport: { width: 960, height: 640 }, deviceScaleFactor: 1 });
  const page = await context.newPage();
  page.errors = [];
  page.on('pageerror', (err) => page.errors.push(err.message));
  page.on('console', (msg) => { if (msg.type() === 'error') page.errors.push(msg.text()); });
  return page;
}

// What each browser test file starts in before() and ends in after(): a pointdagd serving the viewer
// (one ingest worker), Chromium and one page. close() is safe after a start that failed half-way.
export async function openSession({ token = null } = {}) {
  const session = {
    daemon: null, browser: null, page: null,
    async close() {
      if (session.browser) await session.browser.close();
      if (session.daemon) await session.daemon.stop();
    },
  };
  try {
    session.daemon = await Daemon.start({ token, webDir: config.webDir, workers: 1, startSeconds: 30 });
    session.browser = await launchChromium();
    session.page = await newPage(session.browser);
  } catch (err) {
    await session.close();
    throw err;
  }
  return session;
}
