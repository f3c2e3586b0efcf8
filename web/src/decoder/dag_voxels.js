// The voxels of a decoded DAG (dag_stream.js) in Morton order, as Svdag::MortonCodes visits them,
// written as integer cell coordinates (x, y, z), and in mipmap mode each voxel's color picked from
// the node colors by its depth-first pre-order rank (MipVoxelIndices in color/mip_colors.cc).
import { COUNT_MIPMAP } from './dag_stream.js';

// Offsets of brick bit b (= 8 * cell + voxel, cell and voxel each x<<2 | y<<1 | z) in the 4x4x4 brick.
const BRICK_DX = new Uint8Array(64);
const BRICK_DY = new Uint8Array(64);
const BRICK_DZ = new Uint8Array(64);
for (let b = 0; b < 64; ++b) {
  const cell = b >> 3;
  const voxel = b & 7;
  BRICK_DX[b] = (((cell >> 2) & 1) << 1) | ((voxel >> 2) & 1);
  BRICK_DY[b] = (((cell >> 1) & 1) << 1) | ((voxel >> 1) & 1);
  BRICK_DZ[b] = ((cell & 1) << 1) | (voxel & 1);
}

// `count`: the DAG's voxel count (dag.rootVoxels). `nodeColors`: RGB per color index (per node in
// mipmap mode, per voxel in leaf mode) or null. -> {coords, colors (RGB per voxel or null)}.
export function enumerateVoxels(dag, count, nodeColors) {
  const coords = dag.depth > 16 ? new Uint32Array(3 * count) : new Uint16Array(3 * count);
  const mip = dag.mode === COUNT_MIPMAP;
  // Leaf mode: color index = Morton rank, so the colors are already in voxel order.
  const gather = mip && nodeColors !== null;
  const colors = gather ? new Uint8Array(3 * count) : nodeColors;
  const { levels, masks, firstChild, children, brickLo, brickHi } = dag;
  let out = 0;    // 3 * voxels written
  let rank = 0;   // pre-order rank of the next node (mipmap mode)

  const emitBrick = (brick, bx, by, bz) => {
    ++rank;  // the brick itself
    const x = bx << 2, y = by << 2, z = bz << 2;
    for (let half = 0; half < 2; ++half) {
      const word = half ? brickHi[brick] : brickLo[brick];
      for (let c = 0; c < 4; ++c) {
        let m = (word >>> (8 * c)) & 0xff;
        if (!m) continue;
        ++rank;  // the occupied 2x2x2 cell
        const base = 8 * (4 * half + c);
        while (m) {
          const b = base + 31 - Math.clz32(m & -m);
          m &= m - 1;
          coords[out] = x | BRICK_DX[b];
          coords[out + 1] = y | BRICK_DY[b];
          coords[out + 2] = z | BRICK_DZ[b];
          if (gather) {
            const from = 3 * rank;
            colors[out] = nodeColors[from];
            colors[out + 1] = nodeColors[from + 1];
            colors[out + 2] = nodeColors[from + 2];
          }
          out += 3;
          ++rank;
        }
      }
    }
  };

  if (levels === 0) {
    emitBrick(0, 0, 0, 0);
    return { coords, colors };
  }
  // Depth-first over the internal levels with an explicit stack: per level, the mask bits still
  // to visit, the next child slot, and the node's cell coordinates.
  const pending = new Int32Array(levels);
  const slot = new Int32Array(levels);
  const xs = new Int32Array(levels);
  const ys = new Int32Array(levels);
  const zs = new Int32Array(levels);
  pending[0] = masks[0][0];
  slot[0] = firstChild[0][0];
  rank = 1;  // the root
  let level = 0;
  while (level >= 0) {
    const bits = pending[level];
    if (bits === 0) {
      --level;
      continue;
    }
    const octant = 31 - Math.clz32(bits & -bits);
    pending[level] = bits & (bits - 1);
    const child = children[level][slot[level]++];
    const x = (xs[level] << 1) | (octant >> 2);
    const y = (ys[level] << 1) | ((octant >> 1) & 1);
    const z = (zs[level] << 1) | (octant & 1);
    if (level + 1 === levels) {
      emitBrick(child, x, y, z);
    } else {
      ++level;
      pending[level] = masks[level][child];
      slot[level] = firstChild[level][child];
      xs[level] = x;
      ys[level] = y;
      zs[level] = z;
      ++rank;
    }
  }
  return { coords, colors };
}
