// Strict JSON as nlohmann::json reads it (codec/pointdag/json_text.cc), for metadata that came from
// outside: nesting bounded (64), invalid UTF-8 and lone surrogates refused, a float that overflows
// refused, and every number's kind kept as nlohmann keeps it, because the C++ reader's type checks
// depend on it: an integer literal without '-' up to 2^64-1 is 'unsigned', one with '-' down to
// -2^63 is 'integer', anything else is 'float' ("voxels": 5.0 is not an integer there).
import { corrupt } from './pdag_error.js';

export const MAX_JSON_DEPTH = 64;

const UTF8 = new TextDecoder('utf-8', { fatal: true });

// What parseJson returns: plain JS values, plus the kind of each object member that is a number.
export class JsonDocument {
  constructor(root, kinds) {
    this.root = root;
    this.kinds = kinds;  // WeakMap: object -> Map(key -> 'unsigned' | 'integer' | 'float')
  }
  numberKind(object, key) {
    return this.kinds.get(object)?.get(key);
  }
}

class Parser {
  constructor(text) {
    this.s = text;
    this.i = 0;
    this.kinds = new WeakMap();
    this.lastKind = null;  // kind of the number parseValue just read
  }
  fail(why) {
    throw corrupt(`not valid JSON: ${why} at offset ${this.i}`);
  }
  ws() {
    const s = this.s;
    for (;;) {
      const c = s.charCodeAt(this.i);
      if (c === 0x20 || c === 0x0a || c === 0x0d || c === 0x09) ++this.i;
      else return;
    }
  }
  value(depth) {
    this.ws();
    this.lastKind = null;
    const c = this.s.charCodeAt(this.i);
    if (c === 0x7b) return this.object(depth + 1);
    if (c === 0x5b) return this.array(depth + 1);
    if (c === 0x22) return this.string();
    if (c === 0x2d || (c >= 0x30 && c <= 0x39)) return this.number();
    for (const [word, v] of [['true', true], ['false', false], ['null', null]]) {
      if (this.s.startsWith(word, this.i)) {
        this.i += word.length;
        return v;
      }
    }
    return this.fail('unexpected character');
  }
  object(depth) {
    if (depth > MAX_JSON_DEPTH) this.fail(`nested deeper than ${MAX_JSON_DEPTH} levels`);
    ++this.i;
    const out = {};
    let kinds = null;
    this.ws();
    if (this.s.charCodeAt(this.i) === 0x7d) {
      ++this.i;
      return out;
    }
    for (;;) {
      this.ws();
      if (this.s.charCodeAt(this.i) !== 0x22) this.fail("expected a member's name");
      const key = this.string();
      this.ws();
      if (this.s.charCodeAt(this.i) !== 0x3a) this.fail("expected ':'");
      ++this.i;
      const v = this.value(depth);
      // Duplicate names: the last wins, as in nlohmann. "__proto__" stays an own member, as in JSON.parse.
      if (key === '__proto__') Object.defineProperty(out, key, { value: v, enumerable: true, writable: true, configurable: true });
      else out[key] = v;
      if (this.lastKind !== null) (kinds ??= new Map()).set(key, this.lastKind);
      else kinds?.delete(key);
      this.ws();
      const c = this.s.charCodeAt(this.i++);
      if (c === 0x7d) break;
      if (c !== 0x2c) this.fail("expected ',' or '}'");
    }
    if (kinds) this.kinds.set(out, kinds);
    this.lastKind = null;
    return out;
  }
  array(depth) {
    if (depth > MAX_JSON_DEPTH) this.fail(`nested deeper than ${MAX_JSON_DEPTH} levels`);
    ++this.i;
    const out = [];
    this.ws();
    if (this.s.charCodeAt(this.i) === 0x5d) {
      ++this.i;
      return out;
    }
    for (;;) {
      out.push(this.value(depth));
      this.ws();
      const c = this.s.charCodeAt(this.i++);
      if (c === 0x5d) break;
      if (c !== 0x2c) this.fail("expected ',' or ']'");
    }
    this.lastKind = null;
    return out;
  }
  string() {
    const s = this.s;
    let out = '';
    let start = ++this.i;
    for (;;) {
      if (this.i >= s.length) this.fail('unterminated string');
      const c = s.charCodeAt(this.i);
      if (c === 0x22) break;
      if (c < 0x20) this.fail('control character in a string');
      if (c !== 0x5c) {
        ++this.i;
        continue;
      }
      out += s.slice(start, this.i);
      const e = s[this.i + 1];
      this.i += 2;
      const simple = { '"': '"', '\\': '\\', '/': '/', b: '\b', f: '\f', n: '\n', r: '\r', t: '\t' }[e];
      if (simple !== undefined) {
        out += simple;
      } else if (e === 'u') {
        let u = this.hex4();
        if (u >= 0xdc00 && u <= 0xdfff) this.fail('lone low surrogate');
        if (u >= 0xd800 && u <= 0xdbff) {
          if (s[this.i] !== '\\' || s[this.i + 1] !== 'u') this.fail('high surrogate without its low half');
          this.i += 2;
          const lo = this.hex4();
          if (lo < 0xdc00 || lo > 0xdfff) this.fail('high surrogate without its low half');
          out += String.fromCharCode(u, lo);
          u = -1;
        }
        if (u >= 0) out += String.fromCharCode(u);
      } else {
        this.fail('invalid escape');
      }
      start = this.i;
    }
    out += s.slice(start, this.i);
    ++this.i;
    return out;
  }
  hex4() {
    const h = this.s.slice(this.i, this.i + 4);
    if (!/^[0-9a-fA-F]{4}$/.test(h)) this.fail('invalid \\u escape');
    this.i += 4;
    return parseInt(h, 16);
  }
  number() {
    const s = this.s;
    const start = this.i;
    const digits = () => {
      const from = this.i;
      while (s.charCodeAt(this.i) >= 0x30 && s.charCodeAt(this.i) <= 0x39) ++this.i;
      return this.i - from;
    };
    const negative = s.charCodeAt(this.i) === 0x2d;
    if (negative) ++this.i;
    if (s.charCodeAt(this.i) === 0x30) ++this.i;
    else if (digits() === 0) this.fail('expected a digit');
    let integral = true;
    if (s.charCodeAt(this.i) === 0x2e) {
      ++this.i;
      integral = false;
      if (digits() === 0) this.fail("expected a digit after '.'");
    }
    const e = s.charCodeAt(this.i);
    if (e === 0x65 || e === 0x45) {
      ++this.i;
      integral = false;
      const sign = s.charCodeAt(this.i);
      if (sign === 0x2b || sign === 0x2d) ++this.i;
      if (digits() === 0) this.fail('expected a digit in the exponent');
    }
    const text = s.slice(start, this.i);
    const v = Number(text);
    if (integral && text.length > 15) {
      const big = BigInt(text);  // nlohmann keeps what fits in 64 bits as an integer
      if (negative ? big < -(1n << 63n) : big > (1n << 64n) - 1n) integral = false;
    }
    if (!integral && !Number.isFinite(v)) this.fail('number overflow');
    this.lastKind = integral ? (negative ? 'integer' : 'unsigned') : 'float';
    return v;
  }
}

// `bytes`: UTF-8 text (a leading byte-order mark is skipped). Throws PdagError 'Corrupt'.
export function parseJson(bytes) {
  let text;
  try {
    text = UTF8.decode(bytes);
  } catch {
    throw corrupt('not valid JSON: invalid UTF-8');
  }
  const p = new Parser(text);
  const root = p.value(0);
  p.ws();
  if (p.i !== text.length) p.fail('text after the value');
  return new JsonDocument(root, p.kinds);
}
