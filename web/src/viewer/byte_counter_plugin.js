// A TilesRenderer plugin that counts the body bytes the renderer fetches: .glb tiles apart from
// the rest (tileset.json), for the HUD and for comparing with the .pdag tiles of the same view.
export class ByteCounterPlugin {
  constructor() {
    this.name = 'BYTE_COUNTER';
    this.tileBytes = 0;
    this.tiles = 0;
    this.otherBytes = 0;
  }

  async fetchData(url, options) {
    const res = await fetch(url, options);
    if (!res.ok) return res;
    const body = await res.arrayBuffer();
    if (/\.glb(\?|$)/.test(url)) {
      this.tileBytes += body.byteLength;
      this.tiles++;
    } else {
      this.otherBytes += body.byteLength;
    }
    return new Response(body, { status: res.status, statusText: res.statusText, headers: res.headers });
  }
}
