// Shades points by their voxel's light (the per-tile shadow layer, SHADOW_FORMAT.md §2) in the
// point material: a tile with a layer gets a per-point attribute `shadowLight` (0..255, normalized)
// and a shaded twin of its material, whose fragment colour is multiplied by
//   ambient + (1 - ambient) * light / 255
// after the output colour conversion, so a shadowed voxel is drawn at `ambient` times the colour the
// unshaded view shows. One uniform shared by every shaded material turns the shading on and off:
// toggling costs no fetch, no decode and no shader compile.
import * as THREE from 'three';

export const SHADOW_AMBIENT = 0.35;

const VERTEX_DECLARATIONS = `
attribute float shadowLight;
uniform float shadowStrength;
varying float vShadowFactor;`;
const VERTEX_FACTOR = `
vShadowFactor = mix(1.0, ${SHADOW_AMBIENT.toFixed(4)} + ${(1 - SHADOW_AMBIENT).toFixed(4)} * shadowLight, shadowStrength);`;

export class ShadowShading {
  constructor() {
    this.strength = { value: 0 };
    this.twins = new WeakMap(); // plain material -> its shaded twin
  }

  get enabled() {
    return this.strength.value > 0;
  }

  setEnabled(on) {
    this.strength.value = on ? 1 : 0;
  }

  // Gives the tile's points their light (Uint8Array, one byte per voxel) and the shaded material.
  attach(points, light) {
    points.geometry.setAttribute('shadowLight', new THREE.BufferAttribute(light, 1, true));
    points.material = this.shadedTwin(points.material);
  }

  shadedTwin(material) {
    let twin = this.twins.get(material);
    if (!twin) {
      twin = material.clone();
      twin.onBeforeCompile = (shader) => this.patch(shader);
      twin.customProgramCacheKey = () => 'pointdag-shadow-shading';
      material.addEventListener('dispose', () => twin.dispose());
      this.twins.set(material, twin);
    }
    return twin;
  }

  patch(shader) {
    shader.uniforms.shadowStrength = this.strength;
    shader.vertexShader = shader.vertexShader
      .replace('#include <common>', `#include <common>${VERTEX_DECLARATIONS}`)
      .replace('#include <color_vertex>', `#include <color_vertex>${VERTEX_FACTOR}`);
    shader.fragmentShader = shader.fragmentShader
      .replace('#include <common>', '#include <common>\nvarying float vShadowFactor;')
      .replace('#include <colorspace_fragment>', '#include <colorspace_fragment>\ngl_FragColor.rgb *= vShadowFactor;');
  }
}
