// The three.js scene both dataset views draw into: a WebGL canvas filling its container, a
// perspective camera whose up is the frame's Z (the datasets' ENU frame) or a model's Y, OrbitControls,
// and a render loop that draws on demand (after a camera move, a resize or a tile load), calling
// onFrame() first.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

export const BACKGROUND = 0x1b2230;

// Which axis of the dataset's frame points up: Z for georeferenced scans (ENU) and most LIDAR; Y for
// photogrammetry statues and many PLY models; -Y for depth cameras (their Y points down). `view`: the
// default view, from the "south-west" 40 degrees above the horizon, in that frame (east X, north up x X).
export const UP_AXES = {
  z: { label: 'Z up', up: [0, 0, 1], view: [-0.45, -0.75, 0.85] },
  y: { label: 'Y up', up: [0, 1, 0], view: [-0.45, 0.85, 0.75] },
  '-y': { label: '−Y up', up: [0, -1, 0], view: [-0.45, -0.85, -0.75] },
};

export class SceneView {
  // srgbColors: the points' vertex colors are sRGB bytes (our .pdag tiles), drawn as they are; else
  // they are linear, as glTF's (3D Tiles), and converted to sRGB on output as three.js does.
  constructor(container, upAxis = 'z', { srgbColors = true } = {}) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: false, powerPreference: 'high-performance' });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    // Scans store sRGB bytes, and their points are drawn with exactly those: three.js takes vertex
    // colors as linear and would brighten them on output to sRGB (a violet 68 1 84 drawn as 143 13 156).
    if (srgbColors) this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    this.renderer.setClearColor(new THREE.Color().setHex(BACKGROUND, this.renderer.outputColorSpace), 1);
    container.append(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(50, 1, 0.1, 1000);
    this.moveListeners = [];
    this.upAxis = upAxis in UP_AXES ? upAxis : 'z';
    this.camera.up.set(...UP_AXES[this.upAxis].up);
    this.controls = this.makeControls();
    this.radius = 1;
    this.onFrame = () => {};
    this.frameMs = 0;
    this.frames = 0;
    this.dirty = true;
    this.resizeObserver = new ResizeObserver(() => this.resize());
    this.resizeObserver.observe(container);
    this.resize();
    this.loop = this.loop.bind(this);
    requestAnimationFrame(this.loop);
  }

  requestRender() {
    this.dirty = true;
  }

  // OrbitControls orbit about the camera's up as it was when they were made: a new up needs new controls.
  makeControls() {
    const controls = new OrbitControls(this.camera, this.renderer.domElement);
    controls.screenSpacePanning = true;
    controls.zoomToCursor = true; // the wheel zooms into the part of the data under the mouse
    controls.addEventListener('change', () => this.requestRender());
    controls.addEventListener('start', () => this.moveListeners.forEach((listener) => listener()));
    return controls;
  }

  // Called when the user starts moving the camera.
  onUserMove(listener) {
    this.moveListeners.push(listener);
  }

  // Turns the view to another up axis (a key of UP_AXES) about the same target; fit() again to see it all.
  setUpAxis(axis) {
    if (!(axis in UP_AXES)) throw new Error(`unknown up axis ${axis}`);
    this.upAxis = axis;
    this.camera.up.set(...UP_AXES[axis].up);
    const target = this.controls.target.clone();
    this.controls.dispose();
    this.controls = this.makeControls();
    this.controls.target.copy(target);
    this.controls.update();
    this.requestRender();
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth);
    const hgt = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, hgt);
    this.camera.aspect = w / hgt;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  // Drawing-buffer height in pixels: what a tile's projected voxel size is measured against.
  heightPx() {
    return this.renderer.domElement.height;
  }

  // Frames `box` (THREE.Box3, world frame) from the default direction: the camera looks at its
  // centre from the nearest distance at which all 8 corners are inside the view (with a margin).
  fit(box) {
    const centre = box.getCenter(new THREE.Vector3());
    this.radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
    const viewDirection = new THREE.Vector3(...UP_AXES[this.upAxis].view).normalize();
    const forward = viewDirection.clone().negate();
    const right = new THREE.Vector3().crossVectors(forward, this.camera.up).normalize();
    const up = new THREE.Vector3().crossVectors(right, forward);
    const tanV = Math.tan(THREE.MathUtils.degToRad(this.camera.fov / 2)) * 0.95;
    const tanH = tanV * this.camera.aspect;
    let distance = 0;
    for (const corner of boxCorners(box)) {
      const q = corner.sub(centre);
      // A corner at depth D - q.forward must satisfy |q.right| <= tanH * depth and |q.up| <= tanV * depth.
      const depth = Math.max(Math.abs(q.dot(right)) / tanH, Math.abs(q.dot(up)) / tanV);
      distance = Math.max(distance, q.dot(forward) + depth);
    }
    this.controls.target.copy(centre);
    this.camera.position.copy(centre).addScaledVector(viewDirection, Math.max(distance, this.radius * 1e-3));
    this.controls.update();
    this.requestRender();
  }

  // Near and far planes that follow the camera's distance, so that depth precision holds at every zoom.
  updateClipPlanes() {
    const distance = this.camera.position.distanceTo(this.controls.target);
    this.camera.near = Math.max(distance * 1e-3, this.radius * 1e-5);
    this.camera.far = distance + this.radius * 4;
    this.camera.updateProjectionMatrix();
  }

  // Screen rectangle (CSS pixels of the canvas) of the points (world frame) in front of the camera.
  project(points) {
    this.camera.updateMatrixWorld();
    const rect = { x0: Infinity, y0: Infinity, x1: -Infinity, y1: -Infinity };
    const w = this.container.clientWidth;
    const hgt = this.container.clientHeight;
    const view = new THREE.Vector3();
    for (const p of points) {
      view.copy(p).applyMatrix4(this.camera.matrixWorldInverse);
      if (view.z >= 0) continue; // behind the camera
      const ndc = p.clone().project(this.camera);
      rect.x0 = Math.min(rect.x0, ((ndc.x + 1) / 2) * w);
      rect.x1 = Math.max(rect.x1, ((ndc.x + 1) / 2) * w);
      rect.y0 = Math.min(rect.y0, ((1 - ndc.y) / 2) * hgt);
      rect.y1 = Math.max(rect.y1, ((1 - ndc.y) / 2) * hgt);
    }
    return rect;
  }

  loop() {
    requestAnimationFrame(this.loop);
    if (!this.dirty) return;
    this.dirty = false;
    const t0 = performance.now();
    this.updateClipPlanes();
    this.camera.updateMatrixWorld();
    this.onFrame();
    this.renderer.render(this.scene, this.camera);
    const ms = performance.now() - t0;
    this.frameMs = this.frames++ === 0 ? ms : this.frameMs * 0.8 + ms * 0.2;
  }
}

// The 8 corners of a THREE.Box3, transformed by `matrix` when given.
export function boxCorners(box, matrix = null) {
  const corners = [];
  for (let i = 0; i < 8; ++i) {
    const c = new THREE.Vector3(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z);
    corners.push(matrix ? c.applyMatrix4(matrix) : c);
  }
  return corners;
}
