// Number formatting for tables and the HUD.
export function formatInt(n) {
  return Number.isFinite(n) ? Math.round(n).toLocaleString('en-US') : '–';
}

export function formatBytes(n) {
  if (!Number.isFinite(n)) return '–';
  const units = ['B', 'KiB', 'MiB', 'GiB'];
  let i = 0;
  while (n >= 1024 && i < units.length - 1) {
    n /= 1024;
    ++i;
  }
  return `${i === 0 ? n : n.toFixed(n < 10 ? 2 : 1)} ${units[i]}`;
}

export function formatFixed(n, digits) {
  return Number.isFinite(n) ? n.toFixed(digits) : '–';
}

// Our size against Draco's on the same voxels (PROTOCOL.md §2 draco.draco_over_ours = Draco's bits over ours).
export function formatDracoRatio(dataset) {
  const r = dataset.draco && dataset.draco.draco_over_ours;
  if (!Number.isFinite(r) || r <= 0) return '–';
  return r >= 1 ? `${r.toFixed(2)}× smaller` : `${(1 / r).toFixed(2)}× larger`;
}

export function formatLength(metres, georeferenced) {
  return `${formatFixed(metres, metres < 0.1 ? 3 : 2)}${georeferenced ? ' m' : ' (scan units)'}`;
}
