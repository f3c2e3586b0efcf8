// decodePdag(bytes): a .pdag tile -> its voxels and colors, exactly as codec/pointdag/decode_pdag.cc
// DecodePdag gives them (and `pointdag decode` writes them), with the same checks in the same order
// and the same limits (proto/PDAG_FORMAT.md §4): what the metadata declares only bounds the
// geometry decoder; nothing is allocated by a count the bytes have not vouched for.
//
// Returns {meta, depth, voxelSize, origin: [x, y, z], count,
//          coords: Uint16Array(3 * count) (Uint32Array when depth > 16), cell (i, j, k) per voxel in Morton order,
//          colors: Uint8Array(3 * count) | null}.
// Voxel centre = origin + (coord + 0.5) * voxelSize. Throws PdagError ('Corrupt', 'ResourceLimit', 'Unsupported').
import { VOXEL_COLORS_ONLY, decodeColors, unsupportedColorCodec } from './color_section.js';
import { COUNT_LEAVES, MAX_DEPTH, decodeDag } from './dag_stream.js';
import { enumerateVoxels } from './dag_voxels.js';
import { COMPACT_SPATIAL_VERSION } from './spatial_coder.js';
import { JsonFields } from './json_fields.js';
import { parsePdagContainer } from './pdag_container.js';
import { corrupt, resourceLimit, unsupported } from './pdag_error.js';

export { PdagError } from './pdag_error.js';

// DecodeLimits of codec/pointdag/pipeline.h.
export const DEFAULT_LIMITS = Object.freeze({ maxVoxels: 2 ** 27, maxNodes: 2 ** 25 });

// Parts of the format that neither this decoder nor the WebAssembly build (web/wasm) reads, refused
// before anything else is decoded, at the same point in both, so that both fail alike.
export function refuseUnsupported(geometry, colors) {
  // (Version 8's second byte is its depth and mode, not a coder.)
  if (geometry.length >= 2 && geometry[0] !== COMPACT_SPATIAL_VERSION && geometry[1] === 0) {
    throw unsupported('the geometry stream is zstd-coded; this decoder reads the range coders only');
  }
  const why = colors ? unsupportedColorCodec(colors[0] & ~VOXEL_COLORS_ONLY) : null;
  if (why) throw unsupported(`${why} are not read by this decoder`);
}

export function decodePdag(bytes, limits = DEFAULT_LIMITS) {
  const { maxVoxels, maxNodes } = { ...DEFAULT_LIMITS, ...limits };
  const file = parsePdagContainer(bytes);
  refuseUnsupported(file.geometry, file.colors);
  const meta = new JsonFields(file.meta, '.pdag metadata');
  const voxels = meta.uint('voxels', Infinity);
  if (voxels > maxVoxels) throw resourceLimit(`.pdag declares ${voxels} voxels, more than the ${maxVoxels} this decoder allows`);
  const depth = meta.int('depth', 2, MAX_DEPTH);
  const voxelSize = meta.number('voxel_size');
  const origin = meta.vec3('origin');
  meta.uintOr('source/points', Infinity, 0);

  // Every unique node has a voxel below it on each level: that bounds the nodes of a true header.
  const dag = decodeDag(file.geometry, Math.min(voxels * depth + 64, maxNodes));
  if (dag.depth !== depth) throw corrupt('.pdag metadata depth disagrees with its geometry');
  // In leaf mode the root's count is the voxel count; in mipmap mode it counts every node, so it
  // bounds what enumerating the voxels and decoding the colors can produce.
  if ((dag.mode === COUNT_LEAVES && dag.rootCount !== voxels) || dag.rootCount < voxels) {
    throw corrupt('.pdag metadata voxel count disagrees with its geometry');
  }
  if (dag.rootCount > maxVoxels) {
    throw resourceLimit(`.pdag geometry holds ${dag.rootCount} nodes, more than the ${maxVoxels} this decoder allows`);
  }
  if (dag.rootVoxels !== voxels) throw corrupt('.pdag metadata voxel count disagrees with its geometry');
  let coords, colors;
  const voxelColorsOnly = file.colors !== null && (file.colors[0] & VOXEL_COLORS_ONLY) !== 0;
  if (voxelColorsOnly && dag.mode === COUNT_LEAVES) {
    throw corrupt('.pdag colors section marks voxel colors only (codec bit 7) in leaf mode');
  }
  if (file.colors && (dag.mode === COUNT_LEAVES || voxelColorsOnly)) {
    // One color per voxel in Morton order: the colors' spatial contexts need the voxels first.
    ({ coords } = enumerateVoxels(dag, voxels, null));
    colors = decodeColors(file.colors, voxels, coords);
  } else {
    const nodeColors = file.colors ? decodeColors(file.colors, dag.rootCount) : null;
    ({ coords, colors } = enumerateVoxels(dag, voxels, nodeColors));
  }
  return { meta: file.meta.root, depth, voxelSize, origin, count: voxels, coords, colors };
}
