// The shadow layers a real pointdagd writes (the C++ encoder, codec/pointdag/shadow/shadow_layer.cc)
// read by the browser's decoder (web/src/decoder/shadow_layer.js): after a shadow job on a real scan
// every tile's layer decodes to the tile's voxel count, byte for byte what the spec's writer gives
// for the same light, and its values mean what SHADOW_FORMAT.md §2 says: 0 or 255 at the finest
// level for one direction, and on a coarser level the mean over the finest voxels a voxel covers.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { decodePdag } from '../../web/src/decoder/decode_pdag.js';
import { SHADOW_KIND_DIRECTION, decodeShadowLayer } from '../../web/src/decoder/shadow_layer.js';
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

test('every tile\'s layer decodes, in the spec writer\'s bytes, with the meaning of SHADOW_FORMAT §2', async (t) => {
  const dataset = await computeShadows(daemon.url, datasetId, { direction: DIRECTION });
  assert.ok(dataset.shadows, 'no `shadows` in the metadata after the job');
  const tiles = await listTiles(daemon.url, datasetId);
  const finest = dataset.levels - 1;
  const cellsPerTile = 2 ** dataset.tile_depth;
  const levels = []; // per level: [{cells: [[x, y, z]], light}]
  let bytes = 0;
  for (const tile of tiles) {
    const r = await fetch(layerUrl(tile));
    assert.equal(r.status, 200, `layer ${tile.level}/${tile.x}/${tile.y}/${tile.z}: ${r.status}`);
    const body = new Uint8Array(await r.arrayBuffer());
    bytes += body.length;
    const layer = decodeShadowLayer(body, tile.voxels);
    assert.equal(layer.kind, SHADOW_KIND_DIRECTION);
    assert.equal(layer.samples, 1);
    assert.deepEqual(body, encodeShadowLayer(layer.light, { kind: layer.kind, samples: layer.samples }),
      'the C++ encoder\'s bytes differ from maximal runs of the same light');
    const { coords } = decodePdag(await fetchTile(daemon.url, datasetId, tile));
    const origin = [tile.x, tile.y, tile.z].map((v) => v * cellsPerTile);
    const cells = Array.from({ length: tile.voxels }, (_, i) => [0, 1, 2].map((a) => origin[a] + coords[3 * i + a]));
    (levels[tile.level] ??= []).push({ cells, light: layer.light });
  }

  // The finest level: one direction lights a voxel or not.
  const lit = new Map(); // finest cell key -> 0 | 1
  let shadowed = 0;
  for (const { cells, light } of levels[finest]) {
    cells.forEach((c, i) => {
      assert.ok(light[i] === 0 || light[i] === 255, `finest voxel ${c} has light ${light[i]}`);
      lit.set(c.join(','), light[i] / 255);
      if (light[i] === 0) shadowed++;
    });
  }
  assert.equal(lit.size, dataset.voxels);
  t.diagnostic(`${tiles.length} layers, ${bytes} bytes for ${dataset.voxels} finest voxels, ${shadowed} shadowed`);
  assert.ok(shadowed > 0 && shadowed < dataset.voxels, `${shadowed} of ${dataset.voxels} finest voxels shadowed`);
  if (Number.isInteger(dataset.shadows.shadowed_voxels)) assert.equal(shadowed, dataset.shadows.shadowed_voxels);

  // Coarser levels: round(255 * the lit share of the finest voxels each voxel covers).
  for (let level = 0; level < finest; ++level) {
    const shift = finest - level;
    const share = new Map(); // level cell key -> [lit, count]
    for (const [key, value] of lit) {
      const parent = key.split(',').map((v) => Number(v) >> shift).join(',');
      const s = share.get(parent) ?? [0, 0];
      s[0] += value;
      s[1]++;
      share.set(parent, s);
    }
    let voxels = 0;
    for (const { cells, light } of levels[level]) {
      cells.forEach((c, i) => {
        const [sum, count] = share.get(c.join(',')) ?? [NaN, 0];
        assert.ok(count > 0, `level ${level} voxel ${c} covers no finest voxel`);
        assert.equal(light[i], Math.round((255 * sum) / count), `level ${level} voxel ${c}: ${sum} of ${count} finest voxels lit`);
        voxels++;
      });
    }
    assert.equal(voxels, share.size, `level ${level}: layers for ${voxels} voxels, ${share.size} covered`);
  }
});
