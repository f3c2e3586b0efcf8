// The home page's table of datasets (GET /v1/datasets, PROTOCOL.md §2).
import { h } from './dom.js';
import { formatBytes, formatDracoRatio, formatFixed, formatInt } from './format.js';

const COLUMNS = ['Name', 'Points', 'Voxels', 'Stored', 'Bits/point', 'vs Draco', 'Views'];

export class DatasetTable {
  constructor(api) {
    this.api = api;
    this.body = h('tbody');
    this.status = h('p.muted#datasets-status', {}, 'Loading…');
    this.element = h('section.card',
      {},
      h('h2', {}, 'Datasets'),
      h('div.table-wrap', {}, h('table#datasets', {},
        h('thead', {}, h('tr', {}, COLUMNS.map((c) => h('th', {}, c)))),
        this.body)),
      this.status);
  }

  // Reloads the list; a refused read (401 when the daemon requires a token for reads) is shown.
  async refresh() {
    try {
      const { datasets } = await this.api.datasets();
      this.body.replaceChildren(...datasets.map((d) => this.row(d)));
      this.status.textContent = datasets.length ? '' : 'No datasets yet: upload a scan below.';
      this.status.classList.remove('error');
    } catch (err) {
      this.status.textContent = `Could not list the datasets: ${err.message}`;
      this.status.classList.add('error');
      throw err;
    }
  }

  row(d) {
    const href = `/datasets/${encodeURIComponent(d.id)}`;
    const draco = d.draco ? `Draco: ${formatFixed(d.draco.bits_per_point, 2)} bits/point (${d.draco.method})` : '';
    return h('tr', {},
      h('td', {}, h('a', { href }, d.name)),
      h('td.num', {}, formatInt(d.source && d.source.points)),
      h('td.num', {}, formatInt(d.voxels)),
      h('td.num', {}, formatBytes(d.stored_bytes)),
      h('td.num', {}, formatFixed(d.bits_per_point, 2)),
      h('td.num', { title: draco }, formatDracoRatio(d)),
      h('td', {}, h('a', { href }, 'points'), ' · ', h('a', { href: `${href}/3dtiles` }, '3D Tiles')));
  }
}
