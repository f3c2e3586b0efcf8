// The "Shadows" switch of a dataset page whose dataset has shadows (metadata `shadows`, PROTOCOL.md
// §3.2): a checkbox in the top bar that calls onChange(on), and for sun hours the legend beside it.
import { h } from './dom.js';
import { SunHoursLegend } from './sun_hours_legend.js';

export class ShadowToggle {
  // shadows: the dataset's `shadows`; ambient: the viewer's darkest shading, for the legend.
  constructor(shadows, ambient, initiallyOn, onChange) {
    this.input = h('input#shadows', { type: 'checkbox', checked: initiallyOn });
    this.legend = shadows.kind === 'sun_hours' ? new SunHoursLegend(shadows, ambient) : null;
    this.element = h('label.toggle#shadows-toggle', { title: ShadowToggle.describe(shadows) }, this.input, 'Shadows');
    this.input.addEventListener('change', () => this.apply(onChange));
    this.apply(onChange);
  }

  apply(onChange) {
    this.legend?.show(this.input.checked);
    onChange(this.input.checked);
  }

  static describe(shadows) {
    if (shadows.kind === 'sun_hours') return `sun hours from ${shadows.time} to ${shadows.until}`;
    if (shadows.time) return `the sun at ${shadows.time}`;
    return Array.isArray(shadows.direction) ? `light travelling along (${shadows.direction.join(', ')})` : 'shadows';
  }
}
