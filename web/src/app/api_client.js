// pointdagd's HTTP API (proto/PROTOCOL.md) as the pages use it: relative-to-origin /v1 URLs, the
// token from TokenStore on every request, errors as ApiError carrying the daemon's message.
import { ApiError } from './api_error.js';

export class ApiClient {
  constructor(tokens) {
    this.tokens = tokens;
  }

  async request(path, init = {}) {
    let res;
    try {
      res = await fetch(path, { ...init, headers: { ...this.tokens.headers(), ...(init.headers || {}) } });
    } catch (err) {
      throw new ApiError(0, `the daemon did not answer (${err.message})`);
    }
    if (!res.ok) throw ApiError.fromBody(res.status, res.statusText, await res.text());
    return res;
  }

  async json(path) {
    return (await this.request(path)).json();
  }

  async bytes(path, signal) {
    return (await this.request(path, { signal })).arrayBuffer();
  }

  datasets() {
    return this.json('/v1/datasets');
  }

  dataset(id) {
    return this.json(`/v1/datasets/${encodeURIComponent(id)}`);
  }

  job(id) {
    return this.json(`/v1/jobs/${encodeURIComponent(id)}`);
  }

  // POST /v1/datasets with the file as the body. XMLHttpRequest rather than fetch: only it reports
  // the bytes sent. Resolves with the job (202), rejects with ApiError (the daemon's text).
  upload(file, params, onProgress) {
    return new Promise((resolve, reject) => {
      const xhr = new XMLHttpRequest();
      xhr.open('POST', `/v1/datasets?${new URLSearchParams(params)}`);
      for (const [k, v] of Object.entries(this.tokens.headers())) xhr.setRequestHeader(k, v);
      xhr.setRequestHeader('Content-Type', 'application/octet-stream');
      xhr.upload.onprogress = (e) => onProgress(e.loaded, e.lengthComputable ? e.total : file.size);
      xhr.onload = () => {
        if (xhr.status === 202) {
          try {
            resolve(JSON.parse(xhr.responseText));
          } catch {
            reject(new ApiError(xhr.status, 'the daemon accepted the upload but its answer is not JSON'));
          }
        } else {
          reject(ApiError.fromBody(xhr.status, xhr.statusText, xhr.responseText));
        }
      };
      // A refusal sent before the body is read may close the connection under the upload: the
      // browser then reports a network error without the answer.
      xhr.onerror = () => reject(new ApiError(0, 'the upload failed: the connection closed (a refusal from the daemon, or the daemon is unreachable)'));
      xhr.send(file);
    });
  }
}
