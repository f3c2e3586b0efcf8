#!/usr/bin/env node
// Builds the viewer that pointdagd serves (contract 3 of the web brief):
//   node web/build.mjs OUTDIR [--wasm-dir DIR]
// writes OUTDIR/index.html (served with no-cache for /, /datasets/{id}, /datasets/{id}/3dtiles)
// and OUTDIR/assets/* with content-hashed names (served as immutable). Everything comes from
// web/node_modules: the page never reaches a CDN or an external font.
// The decode worker is its own entry; its hashed URL reaches the app through `define`
// (POINTDAG_WORKER_URL). When --wasm-dir holds the WASM decoder (pdag_decoder.mjs), it is copied
// into assets under a hashed name and its URL reaches the app the same way (POINTDAG_WASM_URL,
// null without it), which hands it to the worker as its `?wasm=` query parameter.
import { createHash } from 'node:crypto';
import { copyFileSync, existsSync, mkdirSync, readFileSync, renameSync, rmSync, writeFileSync } from 'node:fs';
import { dirname, join, relative, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import * as esbuild from 'esbuild';

const webDir = dirname(fileURLToPath(import.meta.url));

function parseArgs(argv) {
  const args = { outDir: null, wasmDir: null };
  for (let i = 0; i < argv.length; ++i) {
    if (argv[i] === '--wasm-dir') args.wasmDir = argv[++i];
    else if (argv[i].startsWith('--')) throw new Error(`unknown option ${argv[i]}`);
    else if (args.outDir === null) args.outDir = argv[i];
    else throw new Error(`unexpected argument ${argv[i]}`);
  }
  if (!args.outDir) throw new Error('usage: node web/build.mjs OUTDIR [--wasm-dir DIR]');
  return args;
}

function contentHash(bytes) {
  return createHash('sha256').update(bytes).digest('hex').slice(0, 12);
}

// Copies the WASM decoder (web/wasm's output: pdag_decoder.mjs, an ES module with the .wasm
// embedded) into assets as pdag_decoder-HASH.mjs; returns its URL, or null when there is none.
function copyWasm(wasmDir, assetsDir) {
  if (!wasmDir) return null;
  const file = join(wasmDir, 'pdag_decoder.mjs');
  if (!existsSync(file)) {
    console.warn(`build.mjs: no ${file}; the viewer decodes tiles in JavaScript only`);
    return null;
  }
  const bytes = readFileSync(file);
  const name = `pdag_decoder-${contentHash(bytes)}.mjs`;
  copyFileSync(file, join(assetsDir, name));
  return `/assets/${name}`;
}

const common = {
  bundle: true,
  minify: true,
  sourcemap: true,
  target: ['chrome100', 'firefox100', 'safari15'],
  legalComments: 'linked',
  metafile: true,
  logLevel: 'warning',
};

// The script esbuild wrote for `entry` (a path relative to web/), from its metafile.
function outputOf(metafile, entry) {
  const found = Object.entries(metafile.outputs).find(([out, info]) => info.entryPoint === entry && out.endsWith('.js'));
  if (!found) throw new Error(`esbuild wrote no script for ${entry}`);
  return found[0];
}

function assetUrl(outDir, file) {
  return '/' + relative(outDir, resolve(webDir, file)).split('\\').join('/');
}

function indexHtml(scriptUrl, cssUrl) {
  return `<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>pointdag</title>
<link rel="icon" href="data:,">
<link rel="stylesheet" href="${cssUrl}">
<script type="module" src="${scriptUrl}"></script>
</head>
<body>
<noscript>pointdag's viewer needs JavaScript.</noscript>
</body>
</html>
`;
}

async function main() {
  const { outDir: outArg, wasmDir } = parseArgs(process.argv.slice(2));
  const outDir = resolve(outArg);
  // Built beside the output and moved in at the end: a failed build leaves the previous one whole.
  const staging = join(outDir, '.staging');
  const assetsDir = join(staging, 'assets');
  rmSync(staging, { recursive: true, force: true });
  mkdirSync(assetsDir, { recursive: true });

  const wasm = copyWasm(wasmDir, assetsDir);
  const worker = await esbuild.build({
    ...common,
    absWorkingDir: webDir,
    entryPoints: ['src/decoder/decode_worker.js'],
    outdir: assetsDir,
    entryNames: '[name]-[hash]',
    format: 'esm',
  });
  const workerFile = outputOf(worker.metafile, 'src/decoder/decode_worker.js');

  const app = await esbuild.build({
    ...common,
    absWorkingDir: webDir,
    entryPoints: ['src/app/main.js'],
    outdir: assetsDir,
    entryNames: '[name]-[hash]',
    chunkNames: 'chunk-[hash]',
    assetNames: '[name]-[hash]',
    format: 'esm',
    splitting: true, // the home page loads without three.js
    define: {
      POINTDAG_WORKER_URL: JSON.stringify(assetUrl(staging, workerFile)),
      POINTDAG_WASM_URL: JSON.stringify(wasm),
    },
  });
  const appJs = outputOf(app.metafile, 'src/app/main.js');
  const appCss = app.metafile.outputs[appJs].cssBundle;
  if (!appCss) throw new Error('esbuild wrote no stylesheet for src/app/main.js');

  writeFileSync(join(staging, 'index.html'), indexHtml(assetUrl(staging, appJs), assetUrl(staging, appCss)));
  rmSync(join(outDir, 'assets'), { recursive: true, force: true });
  renameSync(assetsDir, join(outDir, 'assets'));
  renameSync(join(staging, 'index.html'), join(outDir, 'index.html'));
  rmSync(staging, { recursive: true, force: true });
  console.log(`build.mjs: wrote ${join(outDir, 'index.html')} and ${join(outDir, 'assets')}` +
              (wasm ? ' (with the WASM decoder)' : ''));
}

main().catch((err) => {
  console.error(`build.mjs: ${err.message}`);
  process.exit(1);
});
