// THREE.Points for a decoded tile (contract 2). The positions stay the integer cell coordinates
// the decoder gives (Uint16, or Uint32 beyond depth 16): the object's matrix maps a cell to its
// voxel centre, origin + (coord + 0.5) * voxelSize, computed in doubles relative to the viewer's
// frame (the dataset centre), so the GPU never sees large coordinates and no per-point work is done.
import * as THREE from 'three';

// paint(points): colors for a tile without its own (height_colors.js); null: drawn in one grey.
export function buildTilePoints(decoded, frameOrigin, materials, paint = null) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(decoded.coords, 3));
  const hasColor = !!decoded.colors;
  if (hasColor) geometry.setAttribute('color', new THREE.BufferAttribute(decoded.colors, 3, true));
  const points = new THREE.Points(geometry, materials.get(decoded.voxelSize, hasColor || !!paint));
  const half = decoded.voxelSize / 2;
  points.position.set(
    decoded.origin[0] - frameOrigin[0] + half,
    decoded.origin[1] - frameOrigin[1] + half,
    decoded.origin[2] - frameOrigin[2] + half);
  points.scale.setScalar(decoded.voxelSize);
  points.matrixAutoUpdate = false;
  points.updateMatrix();
  points.visible = false;
  if (!hasColor && paint) {
    points.userData.paintedByHeight = true;
    paint(points);
  }
  return points;
}
