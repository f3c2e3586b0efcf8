// The real scans the browser tests upload: POINTDAG_DATA_DIR, else ../shared/data beside the project.
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

export function scanPath(name) {
  const dir = process.env.POINTDAG_DATA_DIR || fileURLToPath(new URL('../../../shared/data', import.meta.url));
  const path = join(dir, name);
  if (!existsSync(path)) throw new Error(`${path} is missing: set POINTDAG_DATA_DIR to the folder of test scans (../shared/data)`);
  return path;
}
