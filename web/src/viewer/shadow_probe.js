// Test hook of the shadow toggle (window.pointdagViewer.shadowProbe): where some visible voxels of
// shaded tiles land on screen, named by tile and index, so a test can compare those pixels, with the
// shading on and off, with what the tile's layer says of the voxel. Visible: the nearest voxel at its centre pixel, by a depth buffer of every drawn
// voxel's square as the GPU draws it (gl_PointSize = size · (height / 2) / depth, one depth per
// square). Voxels are taken at an even stride over the shaded tiles, `limit` at most.
import * as THREE from 'three';

// drawn: [{points, voxels}] (TileNodes, or the 3D Tiles view's stand-ins).
// -> [{x, y, tile: 'L/X/Y/Z', index}]: CSS pixels of the canvas; index in the tile's voxel order.
export function probeVoxelLight(drawn, view, limit) {
  const width = view.container.clientWidth;
  const height = view.container.clientHeight;
  const camera = view.camera;
  camera.updateMatrixWorld();
  const pxAtUnitDepth = height / 2; // three's `scale`, in CSS pixels
  const depth = new Float64Array(width * height).fill(Infinity);
  const toView = new THREE.Matrix4();
  const p = new THREE.Vector3();
  // The voxel's centre pixel and view depth, or null when it is not in front of the camera on screen.
  const place = (node, i) => {
    p.fromBufferAttribute(node.points.geometry.attributes.position, i).applyMatrix4(toView);
    const z = -p.z;
    if (z <= camera.near) return null;
    p.applyMatrix4(camera.projectionMatrix);
    if (Math.abs(p.x) > 1 || Math.abs(p.y) > 1) return null;
    return { x: ((p.x + 1) / 2) * width, y: ((1 - p.y) / 2) * height, z };
  };
  const withNode = (node) => toView.multiplyMatrices(camera.matrixWorldInverse, node.points.matrixWorld);

  for (const node of drawn) {
    withNode(node);
    const size = node.points.material.size * pxAtUnitDepth;
    for (let i = 0; i < node.voxels; ++i) {
      const v = place(node, i);
      if (!v) continue;
      const half = size / v.z / 2;
      const x1 = Math.min(width, Math.round(v.x + half));
      const y1 = Math.min(height, Math.round(v.y + half));
      for (let y = Math.max(0, Math.round(v.y - half)); y < y1; ++y) {
        for (let x = Math.max(0, Math.round(v.x - half)); x < x1; ++x) {
          if (v.z < depth[y * width + x]) depth[y * width + x] = v.z;
        }
      }
    }
  }

  const shaded = drawn.filter((n) => n.points.userData.shadow === 'shaded');
  const stride = Math.max(1, Math.ceil(shaded.reduce((sum, n) => sum + n.voxels, 0) / limit));
  const found = [];
  for (const node of shaded) {
    withNode(node);
    for (let i = 0; i < node.voxels; i += stride) {
      const v = place(node, i);
      if (v && depth[Math.floor(v.y) * width + Math.floor(v.x)] >= v.z) found.push({ x: v.x, y: v.y, tile: node.path(), index: i });
    }
  }
  return found;
}
