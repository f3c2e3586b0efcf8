// The 3D Tiles that `pointdag export --3dtiles` writes (the same bytes pointdagd serves), checked
// by tools we did not write: Khronos's glTF validator on every .glb, once as written and once with
// its EXT_meshopt_compression buffers decoded by meshoptimizer's own decoder (the validator does
// not know that extension, so only the decoded copy lets it check accessors, bounds and data).
// The tileset's rules (3D Tiles 1.1: boxes, geometric errors, REPLACE, content that exists) are
// checked here because the official 3d-tiles-validator is not in the npm registry we can reach.
//
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import test from 'node:test';
import { createRequire } from 'node:module';

import { config, requireFile, scan } from './lib/config.mjs';
import { MeshoptDecoder } from '../../web/node_modules/three/examples/jsm/libs/meshopt_decoder.module.js';

const require = createRequire(import.meta.url);
const validator = require('../../web/node_modules/gltf-validator');

function exportTileset() {
  const cli = requireFile(config.cli, 'the pointdag CLI (build it: scripts/build)');
  const las = scan('autzen_trim_pdrf3_rgb.las');
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'pointdag-3dtiles-'));
  const pdag = path.join(dir, 'autzen.pdag');
  execFileSync(cli, ['encode', las, '-o', pdag, '--voxel', '0.3', '--georeference', '--quality', '38'], { stdio: 'pipe' });
  execFileSync(cli, ['export', pdag, '--3dtiles', path.join(dir, 'tiles')], { stdio: 'pipe' });
  return path.join(dir, 'tiles');
}

// A GLB's JSON and BIN chunks (glTF 2.0 §4.4).
function readGlb(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  assert.equal(view.getUint32(0, true), 0x46546c67, 'GLB magic');
  assert.equal(view.getUint32(4, true), 2, 'GLB version');
  assert.equal(view.getUint32(8, true), bytes.byteLength, 'GLB length');
  const jsonLength = view.getUint32(12, true);
  assert.equal(view.getUint32(16, true), 0x4e4f534a, 'first chunk is JSON');
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLength)));
  const binStart = 20 + jsonLength;
  const binLength = view.getUint32(binStart, true);
  assert.equal(view.getUint32(binStart + 4, true), 0x004e4942, 'second chunk is BIN');
  return { json, bin: bytes.subarray(binStart + 8, binStart + 8 + binLength) };
}

function writeGlb(json, bin) {
  const pad = (n) => (4 - (n % 4)) % 4;
  let text = new TextEncoder().encode(JSON.stringify(json));
  text = Uint8Array.from([...text, ...new Array(pad(text.length)).fill(0x20)]);
  const binPadded = new Uint8Array(bin.length + pad(bin.length));
  binPadded.set(bin);
  const out = new Uint8Array(12 + 8 + text.length + 8 + binPadded.length);
  const view = new DataView(out.buffer);
  view.setUint32(0, 0x46546c67, true);
  view.setUint32(4, 2, true);
  view.setUint32(8, out.length, true);
  view.setUint32(12, text.length, true);
  view.setUint32(16, 0x4e4f534a, true);
  out.set(text, 20);
  view.setUint32(20 + text.length, binPadded.length, true);
  view.setUint32(24 + text.length, 0x004e4942, true);
  out.set(binPadded, 28 + text.length);
  return out;
}

// The same asset with every EXT_meshopt_compression bufferView decoded into one plain buffer.
function decompress({ json, bin }) {
  const parts = [];
  let offset = 0;
  const views = json.bufferViews.map((bv) => {
    const ext = bv.extensions?.EXT_meshopt_compression;
    let data;
    if (ext) {
      assert.equal(ext.buffer, 0, 'compressed data lives in the GLB buffer');
      const source = bin.subarray(ext.byteOffset ?? 0, (ext.byteOffset ?? 0) + ext.byteLength);
      data = new Uint8Array(ext.count * ext.byteStride);
      MeshoptDecoder.decodeGltfBuffer(data, ext.count, ext.byteStride, source, ext.mode, ext.filter ?? 'NONE');
    } else {
      data = bin.subarray(bv.byteOffset ?? 0, (bv.byteOffset ?? 0) + bv.byteLength);
    }
    const plain = { buffer: 0, byteOffset: offset, byteLength: data.length };
    if (bv.byteStride) plain.byteStride = bv.byteStride;
    if (bv.target) plain.target = bv.target;
    parts.push(data, new Uint8Array((4 - (data.length % 4)) % 4));
    offset += data.length + ((4 - (data.length % 4)) % 4);
    return plain;
  });
  const merged = new Uint8Array(offset);
  let at = 0;
  for (const p of parts) { merged.set(p, at); at += p.length; }
  const drop = (list) => list?.filter((e) => e !== 'EXT_meshopt_compression');
  const plainJson = { ...json, bufferViews: views, buffers: [{ byteLength: merged.length }],
    extensionsUsed: drop(json.extensionsUsed), extensionsRequired: drop(json.extensionsRequired) };
  if (!plainJson.extensionsRequired?.length) delete plainJson.extensionsRequired;
  return writeGlb(plainJson, merged);
}

async function validate(bytes, uri) {
  const report = await validator.validateBytes(bytes, { uri, maxIssues: 50 });
  return report;
}

function boxCorners(box) {
  const [cx, cy, cz, ax, ay, az, bx, by, bz, qx, qy, qz] = box;
  const corners = [];
  for (const s of [-1, 1]) for (const t of [-1, 1]) for (const u of [-1, 1]) {
    corners.push([cx + s * ax + t * bx + u * qx, cy + s * ay + t * by + u * qy, cz + s * az + t * bz + u * qz]);
  }
  return corners;
}

function insideBox(point, box, slack) {
  const [cx, cy, cz, ...axes] = box;
  const d = [point[0] - cx, point[1] - cy, point[2] - cz];
  for (let i = 0; i < 3; ++i) {
    const a = axes.slice(3 * i, 3 * i + 3);
    const len2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    if (len2 === 0) continue;
    const t = (d[0] * a[0] + d[1] * a[1] + d[2] * a[2]) / len2;
    if (Math.abs(t) > 1 + slack) return false;
  }
  return true;
}

test('3D Tiles from pointdag export pass the glTF validator and the tileset rules', async (t) => {
  const dir = exportTileset();
  const tileset = JSON.parse(fs.readFileSync(path.join(dir, 'tileset.json'), 'utf8'));
  assert.equal(tileset.asset.version, '1.1');
  assert.ok(tileset.geometricError > tileset.root.geometricError, 'the tileset error exceeds the root error');
  assert.equal(tileset.root.refine, 'REPLACE');
  assert.equal(tileset.root.transform?.length, 16, 'the root carries the ENU->ECEF transform');
  // The origin of the ENU frame lies on the Earth's surface (Oregon): |translation| ~ 6371 km.
  const [tx, ty, tz] = tileset.root.transform.slice(12, 15);
  const radius = Math.hypot(tx, ty, tz);
  assert.ok(radius > 6.3e6 && radius < 6.4e6, `ECEF origin radius ${radius}`);

  const glbs = [];
  const walk = (tile, parent) => {
    assert.ok(tile.boundingVolume?.box?.length === 12, 'every tile has a box');
    if (parent) {
      assert.ok(tile.geometricError < parent.geometricError, 'errors fall towards the leaves');
      for (const c of boxCorners(tile.boundingVolume.box)) {
        assert.ok(insideBox(c, parent.boundingVolume.box, 1e-6), 'a child box lies inside its parent box');
      }
    }
    if (!tile.children?.length) assert.equal(tile.geometricError, 0, 'finest tiles have no error');
    if (tile.content) {
      const file = path.join(dir, tile.content.uri);
      assert.ok(fs.existsSync(file), `content ${tile.content.uri} exists`);
      glbs.push({ file, box: tile.boundingVolume.box });
    }
    for (const child of tile.children ?? []) walk(child, tile);
  };
  walk(tileset.root, null);
  assert.ok(glbs.length > 10, `a multi-level tileset (${glbs.length} tiles)`);

  await MeshoptDecoder.ready;
  let points = 0;
  for (const { file, box } of glbs) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const asServed = await validate(bytes, file);
    assert.equal(asServed.issues.numErrors, 0, `${file}: ${JSON.stringify(asServed.issues.messages.slice(0, 5))}`);
    const glb = readGlb(bytes);
    assert.ok(glb.json.extensionsRequired.includes('EXT_meshopt_compression'));
    assert.ok(glb.json.extensionsRequired.includes('KHR_mesh_quantization'));
    const prim = glb.json.meshes[0].primitives[0];
    assert.equal(prim.mode, 0, 'points');
    const plain = await validate(decompress(glb), file);
    assert.equal(plain.issues.numErrors, 0, `${file} decoded: ${JSON.stringify(plain.issues.messages.slice(0, 5))}`);
    assert.equal(plain.issues.numWarnings, 0, `${file} decoded: ${JSON.stringify(plain.issues.messages.slice(0, 5))}`);
    points += glb.json.accessors[prim.attributes.POSITION].count;
    assert.ok(box.length === 12);
  }
  t.diagnostic(`${glbs.length} tiles, ${points} points validated`);
});
