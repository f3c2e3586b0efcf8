// Typed, checked reads of metadata members, as codec/pointdag/container/json_fields.cc makes them:
// a member is named by a path of object keys ("source/points"); a wrong type or range is 'Corrupt'
// naming the member, never an exception of another kind.
import { corrupt } from './pdag_error.js';

const isObject = (v) => typeof v === 'object' && v !== null && !Array.isArray(v);

export class JsonFields {
  constructor(doc, context) {
    this.doc = doc;  // a JsonDocument (json_text.js)
    this.context = context;
  }
  refuse(path, why) {
    return corrupt(`${this.context} '${path}' ${why}`);
  }
  // {value, kind} of the member, or null when absent; a path through a non-object is refused.
  lookup(path) {
    let node = this.doc.root;
    let parent = null;
    let key = null;
    const keys = path.split('/');
    for (let k = 0; k < keys.length; ++k) {
      if (!isObject(node)) throw this.refuse(`${keys.slice(0, k).join('/')}/`, 'is not an object');
      if (!Object.prototype.hasOwnProperty.call(node, keys[k])) return null;
      parent = node;
      key = keys[k];
      node = node[key];
    }
    return { value: node, kind: typeof node === 'number' ? this.doc.numberKind(parent, key) : undefined };
  }
  required(path) {
    const member = this.lookup(path);
    if (!member) throw this.refuse(path, 'is missing');
    return member;
  }
  int(path, min, max) {
    const { value, kind } = this.required(path);
    if (kind !== 'unsigned' && kind !== 'integer') throw this.refuse(path, 'is not an integer');
    if (value < min || value > max) throw this.refuse(path, `is outside ${min}..${max}`);
    return value;
  }
  // Integers above 2^53 lose precision here, which only matters far beyond any limit they meet.
  uint(path, max) {
    const { value, kind } = this.required(path);
    if (kind !== 'unsigned' && kind !== 'integer') throw this.refuse(path, 'is not an integer');
    if (kind !== 'unsigned') throw this.refuse(path, 'is negative');
    if (value > max) throw this.refuse(path, `is above ${max}`);
    return value;
  }
  uintOr(path, max, fallback) {
    return this.lookup(path) ? this.uint(path, max) : fallback;
  }
  number(path) {
    const { value } = this.required(path);
    if (typeof value !== 'number') throw this.refuse(path, 'is not a number');
    return value;  // finite: the parser refuses overflow
  }
  vec3(path) {
    const { value } = this.required(path);
    if (!Array.isArray(value) || value.length !== 3) throw this.refuse(path, 'is not three numbers');
    if (!value.every((v) => typeof v === 'number')) throw this.refuse(path, 'is not three finite numbers');
    return [value[0], value[1], value[2]];
  }
}
