// The per-tile shadow layers of a dataset with shadows (GET /v1/datasets/{id}/shadows/tiles/L/X/Y/Z,
// SHADOW_FORMAT.md §2), fetched once shadows are on: beside each tile the loader fetches, and for
// the tiles already resident when the toggle turns them on. A layer lives with its tile's points
// (their `shadowLight` attribute) and goes when the tile is evicted. A tile whose layer is missing
// (404) or refused by the decoder is drawn unshaded; the view never breaks for a layer.
import { decodeShadowLayer } from '../decoder/shadow_layer.js';

export class ShadowLayers {
  constructor(api, datasetId, shading, onChange) {
    Object.assign(this, { api, datasetId, shading, onChange });
    this.wanted = false; // on once the toggle was first turned on: from then every tile comes with its layer
    this.loading = 0;
    this.bytes = 0;
    this.missing = 0;
    this.failures = 0;
    this.lastError = null;
  }

  // Shading on or off; on, the resident tiles without a layer fetch theirs.
  setEnabled(on, residentNodes) {
    this.shading.setEnabled(on);
    if (on) {
      this.wanted = true;
      for (const node of residentNodes) this.adopt(node);
    }
    this.onChange();
  }

  // The light of the node's voxels (Uint8Array), or null when it has none; never rejects.
  async fetch(node) {
    try {
      const bytes = await this.api.bytes(`/v1/datasets/${encodeURIComponent(this.datasetId)}/shadows/tiles/${node.path()}`);
      this.bytes += bytes.byteLength;
      return decodeShadowLayer(bytes, node.voxels).light;
    } catch (err) {
      if (err.status === 404) {
        this.missing++;
      } else {
        this.failures++;
        this.lastError = `shadow layer ${node.path()}: ${err.message}`;
        console.warn(this.lastError);
      }
      return null;
    }
  }

  // The shading as the viewers' state() reports it, for the drawn nodes: how many are shaded, drawn
  // without a layer (missing or refused), or waiting for theirs.
  state(drawn) {
    const drawnAs = (what) => drawn.filter((n) => n.points?.userData.shadow === what).length;
    return {
      enabled: this.shading.enabled, tilesShaded: drawnAs('shaded'), tilesWithoutLayer: drawnAs('none'),
      loading: this.loading, bytesFetched: this.bytes, missing: this.missing, errors: this.failures, lastError: this.lastError,
    };
  }

  // Gives the node's resident points their layer: `pending` (a fetch() started beside the tile's),
  // else a fetch of its own when shadows are wanted. node: {points (THREE.Points, null once
  // evicted), voxels, path() 'L/X/Y/Z'}, a TileNode or the 3D Tiles view's stand-in. The points'
  // userData.shadow says how it went: 'loading', 'shaded' or 'none'.
  adopt(node, pending = null) {
    const points = node.points;
    if (!points || points.userData.shadow) return;
    if (!pending) {
      if (!this.wanted) return;
      pending = this.fetch(node);
    }
    points.userData.shadow = 'loading';
    this.loading++;
    pending.then((light) => {
      this.loading--;
      if (node.points !== points) return; // evicted meanwhile: the layer goes with it
      points.userData.shadow = light ? 'shaded' : 'none';
      if (light) this.shading.attach(points, light);
      this.onChange();
    });
  }
}
