// The legend of a sun-hours shadow layer: the shading from the darkest (never lit over the
// period: `ambient` times the colour) to the full colour (lit at every sample), in hours of sun.
import { h } from './dom.js';

// shadows: the dataset's `shadows` metadata (PROTOCOL.md §3.2); ambient: the darkest factor.
export class SunHoursLegend {
  constructor(shadows, ambient) {
    const hours = shadows.hours ?? (Date.parse(shadows.until) - Date.parse(shadows.time)) / 3_600_000;
    const top = Number.isFinite(hours) && hours > 0 ? `${+hours.toFixed(1)} h` : 'all samples';
    const dark = Math.round(255 * ambient);
    this.element = h('div.shadow-legend#shadow-legend', { hidden: true },
      h('span.legend-title', {}, `Sun hours (${shadows.samples} samples)`),
      h('span.legend-bar', { style: `background: linear-gradient(to right, rgb(${dark},${dark},${dark}), #fff)` }),
      h('span.legend-ends', {}, h('span', {}, '0 h'), h('span', {}, top)));
  }

  show(visible) {
    this.element.hidden = !visible;
  }
}
