// The shadow layers a real pointdagd writes (the C++ encoder, codec/pointdag/shadow/shadow_layer.cc)
// read by the browser's decoder (web/src/decoder/shadow_layer.js): after a shadow job on a real scan
// every tile's layer decodes to the tile's voxel count, byte for byte what the spec's writer gives
// for the same light (either version), and its values mean
// what SHADOW_FORMAT.md §2 says: at the finest level the share of the lights that reach the voxel
// (0 or 255 for one direction), on a coarser level the mean over the finest voxels it covers.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { decodePdag } from '../../web/src/decoder/decode_pdag.js';
import { SHADOW_KIND_DIRECTION, SHADOW_KIND_SUN_HOURS, decodeShadowLayer } from '../../web/src/decoder/shadow_layer.js';
import { scan } from './lib/config.mjs';
import { Daemon, computeShadows, fetchTile, ingest, listTiles } from './lib/pointdagd.mjs';
import { encodeShadowLayer } from './lib/shadow_layer_writer.mjs';

const DIRECTION = [0.6, 0.3, -1]; // 56 degrees above the horizon: trees shadow the ground beside them

let daemon;
let datasetId;

before(async () => {
  daemon = await Daemon.start({ workers: 1 });
  datasetId = await ingest(daemon.url, scan('autzen_trim_pdrf3_rgb.las'), { name: 'autzen-shadow-layers' });
});

after(async () => {
  if (daemon) await daemon.stop();
});

const layerUrl = (t) => `${daemon.url}/v1/datasets/${datasetId}/shadows/tiles/${t.level}/${t.x}/${t.y}/${t.z}`;

test('a dataset without shadows has no layers (404) and `shadows` null', async () => {
  const dataset = await (await fetch(`${daemon.url}/v1/datasets/${datasetId}`)).json();
  assert.equal(dataset.shadows ?? null, null);
  const r = await fetch(layerUrl({ level: 0, x: 0, y: 0, z: 0 }));
  assert.equal(r.status, 404);
  assert.equal(typeof (await r.json()).error, 'string');
});

// Every tile's layer of the dataset's current set: decoded, checked against its version's bytes,
// and against the meaning of its values. Returns a line for the diagnostics.
async function checkLayers(dataset, kind) {
  const { samples } = dataset.shadows;
  const tiles = await listTiles(daemon.url, datasetId);
  const finest = dataset.levels - 1;
  const cellsPerTile = 2 ** dataset.tile_depth;
  const levels = []; // per level: [{cells: [[x, y, z]], light}]
  let bytes = 0;
  const versions = new Set();
  for (const tile of tiles) {
    const r = await fetch(layerUrl(tile));
    assert.equal(r.status, 200, `layer ${tile.level}/${tile.x}/${tile.y}/${tile.z}: ${r.status}`);
    const body = new Uint8Array(await r.arrayBuffer());
    bytes += body.length;
    versions.add(body[4]);
    const layer = decodeShadowLayer(body, tile.voxels);
    assert.equal(layer.kind, kind);
    assert.equal(layer.samples, samples);
    // The C++ writer's bytes are the spec's writer's for the same light (version 1: maximal runs;
    // version 2: runs of 3 or more, literal strings between).
    assert.deepEqual(body, encodeShadowLayer(layer.light, { kind, samples, version: body[4] }),
      `the C++ encoder's version ${body[4]} bytes differ from the spec's writer's for the same light`);
    const { coords } = decodePdag(await fetchTile(daemon.url, datasetId, tile));
    const origin = [tile.x, tile.y, tile.z].map((v) => v * cellsPerTile);
    const cells = Array.from({ length: tile.voxels }, (_, i) => [0, 1, 2].map((a) => origin[a] + coords[3 * i + a]));
    (levels[tile.level] ??= []).push({ cells, light: layer.light });
  }

  // The finest level: round(255 * k / samples) for the k of `samples` lights that reach the voxel
  // (k is recovered exactly from the byte while samples <= 255).
  const reached = new Map(); // finest cell key -> k
  let shadowed = 0;
  for (const { cells, light } of levels[finest]) {
    cells.forEach((c, i) => {
      const k = Math.round((light[i] * samples) / 255);
      assert.equal(light[i], Math.round((255 * k) / samples), `finest voxel ${c} has light ${light[i]}, no share of ${samples} lights`);
      reached.set(c.join(','), k);
      if (k === 0) shadowed++;
    });
  }
  assert.equal(reached.size, dataset.voxels);
  assert.ok(shadowed > 0 && shadowed < dataset.voxels, `${shadowed} of ${dataset.voxels} finest voxels shadowed`);
  assert.equal(shadowed, dataset.shadows.shadowed_voxels);

  // Coarser levels: a rounding of 255 * the mean lit share of the finest voxels each voxel covers
  // (either side of an exact half).
  for (let level = 0; level < finest; ++level) {
    const shift = finest - level;
    const share = new Map(); // level cell key -> [sum of k, finest voxels]
    for (const [key, k] of reached) {
      const parent = key.split(',').map((v) => Number(v) >> shift).join(',');
      const s = share.get(parent) ?? [0, 0];
      s[0] += k;
      s[1]++;
      share.set(parent, s);
    }
    let voxels = 0;
    for (const { cells, light } of levels[level]) {
      cells.forEach((c, i) => {
        const [sum, count] = share.get(c.join(',')) ?? [NaN, 0];
        assert.ok(count > 0, `level ${level} voxel ${c} covers no finest voxel`);
        const exact = (255 * sum) / (count * samples);
        assert.ok(Math.abs(light[i] - exact) <= 0.5 + 1e-9, `level ${level} voxel ${c}: light ${light[i]}, ${sum} of ${count * samples} lights reach its finest voxels`);
        voxels++;
      });
    }
    assert.equal(voxels, share.size, `level ${level}: layers for ${voxels} voxels, ${share.size} covered`);
  }
  return `${dataset.shadows.kind}: ${tiles.length} layers (version ${[...versions].join(', ')}), ${bytes} bytes for ` +
    `${dataset.voxels} finest voxels, ${shadowed} reached by no light`;
}

test('one direction: every tile\'s layer decodes, in the spec writer\'s bytes, 0 or 255 at the finest level, means above', async (t) => {
  const dataset = await computeShadows(daemon.url, datasetId, { direction: DIRECTION });
  assert.equal(dataset.shadows?.kind, 'direction');
  t.diagnostic(await checkLayers(dataset, SHADOW_KIND_DIRECTION));
});

test('sun hours: each finest voxel\'s light is its share of the suns, a coarser voxel\'s the mean', async (t) => {
  // Autzen (Oregon, UTC-7) from 08:00 to 18:00 local time on the solstice: 6 suns.
  const dataset = await computeShadows(daemon.url, datasetId, { time: '2024-06-21T15:00:00Z', until: '2024-06-22T01:00:00Z', samples: 6 });
  assert.equal(dataset.shadows?.kind, 'sun_hours');
  t.diagnostic(await checkLayers(dataset, SHADOW_KIND_SUN_HOURS));
});
