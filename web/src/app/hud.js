// The dataset pages' panel: the dataset's metadata, then live statistics, as label/value rows.
import { h } from './dom.js';

export class Hud {
  constructor() {
    this.meta = h('dl.rows#hud-meta');
    this.stats = h('dl.rows#hud-stats');
    this.element = h('aside.hud', {}, this.meta, h('hr'), this.stats);
  }

  static fill(list, rows) {
    list.replaceChildren(...rows.flatMap(([label, value]) => [h('dt', {}, label), h('dd', {}, String(value))]));
  }

  setMeta(rows) {
    Hud.fill(this.meta, rows);
  }

  setStats(rows) {
    Hud.fill(this.stats, rows);
  }
}
