// The HUD's live rows that both viewers show, from their state(); each viewer says what it fetched
// and may add rows of its own (placed before Status, which stays last).
import { formatInt } from '../app/format.js';

export function statRows(s, frameMs, fetched, extra = []) {
  return [
    ['Tiles on screen', formatInt(s.tilesOnScreen)],
    ['Points on screen', formatInt(s.pointsOnScreen)],
    ['Levels drawn', s.levelsDrawn.join(', ') || '–'],
    ['Frame', `${frameMs.toFixed(1)} ms`],
    ['Loading', s.loading],
    ['Fetched', fetched],
    ...extra,
    ['Status', s.lastError ? `error: ${s.lastError}` : s.finestVisibleLevelDrawn ? 'complete' : 'streaming'],
  ];
}

// The Shadows row of a viewer whose dataset has shadows.
export function shadowRow(s) {
  return ['Shadows', s.shadows.enabled ? `${s.shadows.tilesShaded} of ${s.tilesOnScreen} tiles shaded` : 'off'];
}
