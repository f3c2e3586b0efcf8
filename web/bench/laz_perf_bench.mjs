// laz-perf (LAZ in WebAssembly, npm laz-perf) under Node on the same files as our decoder: decode
// rate on one core, and the sha256 of the records so the table can say both decoders agree.
// Usage: node web/bench/laz_perf_bench.mjs [--runs N] FILE.laz...   (one JSON line per file)
import { readFileSync } from 'node:fs';
import { createHash } from 'node:crypto';
import { basename } from 'node:path';
import { createLazPerf } from 'laz-perf';

const args = process.argv.slice(2);
let runs = 3;
if (args[0] === '--runs') {
  runs = Number(args[1]);
  args.splice(0, 2);
}
const LazPerf = await createLazPerf();

function decodeOnce(bytes) {
  const filePtr = LazPerf._malloc(bytes.length);
  LazPerf.HEAPU8.set(bytes, filePtr);
  const laszip = new LazPerf.LASZip();
  try {
    laszip.open(filePtr, bytes.length);
    const count = laszip.getCount();
    const length = laszip.getPointLength();
    const records = new Uint8Array(count * length);
    const pointPtr = LazPerf._malloc(length);
    const start = process.hrtime.bigint();
    for (let i = 0; i < count; ++i) {
      laszip.getPoint(pointPtr);
      records.set(LazPerf.HEAPU8.subarray(pointPtr, pointPtr + length), i * length);
    }
    const seconds = Number(process.hrtime.bigint() - start) / 1e9;
    LazPerf._free(pointPtr);
    return { count, seconds, records };
  } finally {
    laszip.delete();
    LazPerf._free(filePtr);
  }
}

for (const file of args) {
  const bytes = readFileSync(file);
  try {
    let best = Infinity;
    let last = null;
    for (let r = 0; r < runs; ++r) {
      last = decodeOnce(bytes);
      best = Math.min(best, last.seconds);
    }
    const sha256 = createHash('sha256').update(last.records).digest('hex');
    console.log(JSON.stringify({ file: basename(file), points: last.count, seconds: best,
                                 points_per_second: last.count / best, sha256 }));
  } catch (error) {
    console.log(JSON.stringify({ file: basename(file), error: String(error.message ?? error) }));
  }
}
