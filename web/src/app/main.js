// The viewer's entry: one page per route (contract 3 of the web brief). The dataset pages load
// three.js on demand, so the home page stays small.
import './style.css';
import { ApiClient } from './api_client.js';
import { h } from './dom.js';
import { HomePage } from './home_page.js';
import { TokenStore } from './token_store.js';

async function route(root, api) {
  const path = location.pathname;
  if (path === '/' || path === '/index.html') return new HomePage(root, api);
  const match = path.match(/^\/datasets\/([^/]+)(\/3dtiles)?\/?$/);
  if (match) {
    const id = decodeURIComponent(match[1]);
    const { DatasetPage } = await import('./dataset_page.js');
    return new DatasetPage(root, api, id, match[2] ? '3dtiles' : 'pdag', new URLSearchParams(location.search)).start();
  }
  root.replaceChildren(h('main.home', {}, h('p.error', {}, `No page at ${path}. `), h('a', { href: '/' }, 'Datasets')));
  return null;
}

const root = h('div#app');
document.body.append(root);
route(root, new ApiClient(new TokenStore())).catch((err) => {
  root.append(h('p.error.fatal', { role: 'alert' }, `The viewer failed: ${err.message}`));
  console.error(err);
});
