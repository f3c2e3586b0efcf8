// A TilesRenderer plugin that counts the body bytes of everything the renderer fetches
// (tileset.json and .glb tiles), for the HUD and the benchmark.
export class ByteCounterPlugin {
  constructor() {
    this.name = 'BYTE_COUNTER';
    this.bytes = 0;
    this.files = 0;
  }

  async fetchData(url, options) {
    const res = await fetch(url, options);
    if (!res.ok) return res;
    const body = await res.arrayBuffer();
    this.bytes += body.byteLength;
    this.files++;
    return new Response(body, { status: res.status, statusText: res.statusText, headers: res.headers });
  }
}
