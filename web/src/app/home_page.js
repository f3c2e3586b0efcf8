// Home `/`: the token field, the datasets table and the upload form.
import { h } from './dom.js';
import { DatasetTable } from './dataset_table.js';
import { TokenField } from './token_field.js';
import { UploadForm } from './upload_form.js';

export class HomePage {
  constructor(root, api) {
    this.table = new DatasetTable(api);
    const refresh = () => this.table.refresh().catch((err) => { if (err.status === 401) this.token.attention(); });
    this.token = new TokenField(api.tokens, refresh);
    this.upload = new UploadForm(api, { onDone: refresh, onUnauthorized: () => this.token.attention() });
    root.replaceChildren(
      h('header.top', {}, h('h1', {}, h('a', { href: '/' }, 'pointdag')), h('span.muted', {}, 'compressed point clouds, streamed')),
      h('main.home', {}, this.token.element, this.table.element, this.upload.element));
    refresh();
  }
}
