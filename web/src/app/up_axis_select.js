// The "Up" choice of a dataset page: which axis of the dataset's frame points up (UP_AXES of
// scene_view.js). Georeferenced scans are Z up; statues and meshes from photogrammetry are often Y up,
// depth cameras -Y. The page's ?up= wins, else what was last chosen for this dataset (localStorage),
// else Z.
import { h } from './dom.js';

const KEY = 'pointdag.up.';

export class UpAxisSelect {
  // axes: UP_AXES. this.onChange(axis) runs after the user picks one.
  constructor(datasetId, axes, params) {
    this.onChange = () => {};
    this.key = KEY + datasetId;
    const asked = params.get('up');
    const stored = localStorage.getItem(this.key);
    this.axis = asked in axes ? asked : stored in axes ? stored : 'z';
    this.select = h('select#up-axis', { title: 'which axis of the scan points up' },
      Object.entries(axes).map(([axis, { label }]) => h('option', { value: axis, selected: axis === this.axis }, label)));
    this.element = h('label.toggle#up-axis-label', {}, this.select);
    this.select.addEventListener('change', () => {
      this.axis = this.select.value;
      localStorage.setItem(this.key, this.axis);
      this.onChange(this.axis);
    });
  }
}
