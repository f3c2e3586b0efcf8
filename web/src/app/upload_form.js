// The upload form: POST /v1/datasets with a progress bar for the bytes sent, then GET /v1/jobs/{id}
// polled for its stage and percent, then a link to the dataset. A refusal shows the daemon's text.
import { h } from './dom.js';
import { formatBytes } from './format.js';

const POLL_MS = 400;

export class UploadForm {
  // onDone(job) runs once a job is done (the page refreshes its list); onUnauthorized() when the
  // daemon answers 401 (the page points at the token field).
  constructor(api, { onDone, onUnauthorized }) {
    this.api = api;
    this.onDone = onDone;
    this.onUnauthorized = onUnauthorized;
    this.file = h('input#file', { type: 'file', required: true, accept: '.las,.laz,.ply,.pcd' });
    this.name = h('input#name', { type: 'text', placeholder: 'from the file name', maxlength: '200' });
    this.voxel = h('input#voxel', { type: 'number', min: '0', step: 'any', placeholder: 'auto' });
    this.quality = h('input#quality', { type: 'number', min: '10', max: '80', step: 'any', placeholder: '38' });
    this.button = h('button#upload', { type: 'submit' }, 'Upload');
    this.sendBar = h('progress#send-progress', { max: '1', value: '0' });
    this.sendText = h('span#send-status');
    this.jobBar = h('progress#job-progress', { max: '100', value: '0' });
    this.jobText = h('span#job-status');
    this.result = h('p#upload-result');
    this.error = h('p.error#upload-error', { role: 'alert', hidden: true });
    this.progress = h('div.progress', { hidden: true },
      h('label', {}, 'Sent', this.sendBar, this.sendText),
      h('label', {}, 'Job', this.jobBar, this.jobText));
    this.file.addEventListener('change', () => {
      const f = this.file.files[0];
      if (f && !this.name.value) this.name.placeholder = f.name.replace(/\.[^.]*$/, '');
    });
    const form = h('form#upload-form', { on: { submit: (e) => { e.preventDefault(); this.submit(); } } },
      h('label', {}, 'Scan (LAS, LAZ, COPC, PLY, PCD)', this.file),
      h('label', {}, 'Name', this.name),
      h('label', {}, 'Voxel size (optional)', this.voxel),
      h('label', {}, 'Color quality in dB (optional)', this.quality),
      h('div.actions', {}, this.button));
    this.element = h('section.card', {}, h('h2', {}, 'Upload a scan'), form, this.progress, this.error, this.result);
  }

  params(file) {
    const params = { name: this.name.value.trim() || file.name.replace(/\.[^.]*$/, '') || 'scan' };
    if (this.voxel.value) params.voxel = this.voxel.value;
    if (this.quality.value) params.quality = this.quality.value;
    return params;
  }

  async submit() {
    const file = this.file.files[0];
    if (!file) return this.showError('Choose a file to upload.');
    this.showError(null);
    this.result.replaceChildren();
    this.button.disabled = true;
    this.progress.hidden = false;
    this.setBar(this.jobBar, this.jobText, 0, 'waiting for the upload');
    let job = null;
    try {
      job = await this.api.upload(file, this.params(file), (sent, total) => {
        this.setBar(this.sendBar, this.sendText, total ? sent / total : 0,
          `${formatBytes(sent)} of ${formatBytes(total)}`);
      });
      this.setBar(this.sendBar, this.sendText, 1, `${formatBytes(file.size)} sent`);
      await this.follow(job);
    } catch (err) {
      if (!job) this.setBar(this.jobBar, this.jobText, 0, 'not started');
      if (err.status === 401) this.onUnauthorized();
      this.showError(err.status ? `Refused (${err.status}): ${err.message}` : err.message);
    } finally {
      this.button.disabled = false;
    }
  }

  // Polls the job until it is done or failed.
  async follow(job) {
    for (;;) {
      this.setBar(this.jobBar, this.jobText, job.percent / 100, `${job.stage} — ${job.percent.toFixed(0)}%`);
      if (job.status === 'done') {
        const href = `/datasets/${encodeURIComponent(job.dataset_id)}`;
        this.result.replaceChildren('Done: ', h('a#dataset-link', { href }, `open ${job.params.name || 'the dataset'}`),
          ' · ', h('a', { href: `${href}/3dtiles` }, '3D Tiles'));
        this.onDone(job);
        return;
      }
      if (job.status === 'failed') throw new Error(`The job failed: ${job.error}`);
      await new Promise((r) => setTimeout(r, POLL_MS));
      job = await this.api.job(job.id);
    }
  }

  setBar(bar, text, fraction, label) {
    bar.value = bar.max * Math.min(1, Math.max(0, fraction));
    text.textContent = label;
  }

  showError(message) {
    this.error.hidden = !message;
    this.error.textContent = message || '';
  }
}
