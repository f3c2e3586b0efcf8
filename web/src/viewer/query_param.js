// A positive number from the page's query (?budget=, ?sse=, ...), else `fallback`.
export function positiveParam(params, name, fallback) {
  const v = Number(params.get(name));
  return params.has(name) && Number.isFinite(v) && v > 0 ? v : fallback;
}
