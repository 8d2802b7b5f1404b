// How values, times and ages are shown, and how typed text becomes a value
// of the API contract. No DOM, no state.

import { hex } from './util.js';

export const keyOf = (index, sub) => `${hex(index, 4)}:${sub}`;

export function fmtAge(ms) {
  if (ms === null || ms === undefined || !Number.isFinite(ms)) return '–';
  if (ms < 10_000) return `${(ms / 1000).toFixed(1)} s`;
  if (ms < 120_000) return `${Math.round(ms / 1000)} s`;
  if (ms < 7_200_000) return `${Math.round(ms / 60_000)} min`;
  return `${Math.round(ms / 3_600_000)} h`;
}

export function fmtDuration(s) {
  const d = Math.floor(s / 86400), h = Math.floor(s / 3600) % 24, m = Math.floor(s / 60) % 60;
  if (d) return `${d}d ${h}h`;
  if (h) return `${h}h ${m}m`;
  return `${m}m ${Math.floor(s % 60)}s`;
}

export function fmtTime(ts) {
  const d = new Date(ts);
  if (Number.isNaN(d.getTime())) return String(ts ?? '');
  return d.toLocaleTimeString(undefined, { hour12: false }) + '.' + String(d.getMilliseconds()).padStart(3, '0');
}

export const INT_TYPES = new Set(['i8', 'i16', 'i24', 'i32', 'i40', 'i48', 'i56', 'i64',
                           'u8', 'u16', 'u24', 'u32', 'u40', 'u48', 'u56', 'u64']);
const INT_BITS = (t) => Number(t.slice(1));

// Value as shown: unsigned integers also in hex, because CANopen people read
// status words, codes and identities in hex.
export function fmtValue(value, type) {
  if (value === null || value === undefined) return '–';
  if (typeof value === 'boolean') return value ? 'true' : 'false';
  if (type && type[0] === 'u' && INT_TYPES.has(type)) {
    try {
      const big = BigInt(value);
      return `${big} (0x${big.toString(16).toUpperCase().padStart(Math.ceil(INT_BITS(type) / 4), '0')})`;
    } catch { return String(value); }
  }
  if (typeof value === 'number' && !Number.isInteger(value)) return String(Number(value.toPrecision(7)));
  return String(value);
}

// A chartable number, or null (strings such as vs/os/d are not charted).
export function numeric(value, type) {
  if (typeof value === 'number') return Number.isFinite(value) ? value : null;
  if (typeof value === 'boolean') return value ? 1 : 0;
  if (typeof value === 'string' && type && INT_TYPES.has(type)) {
    const n = Number(value);
    return Number.isFinite(n) ? n : null;
  }
  return null;
}

// Text typed by the user -> JSON value of the contract for `type`.
export function parseInput(text, type) {
  const s = text.trim();
  if (type === 'vs' || type === 'us') return text;
  if (type === 'os' || type === 'd') {
    const h = s.replace(/^0x/i, '').replace(/\s+/g, '');
    if (!/^([0-9a-fA-F]{2})*$/.test(h)) throw new Error('expected hex bytes, e.g. 0a1b2c');
    return h.toLowerCase();
  }
  if (type === 'b') {
    if (/^(1|true|on)$/i.test(s)) return true;
    if (/^(0|false|off)$/i.test(s)) return false;
    throw new Error('expected true or false');
  }
  if (type && INT_TYPES.has(type)) {
    if (!/^-?(0x[0-9a-f]+|\d+)$/i.test(s)) throw new Error('expected an integer (decimal or 0x hex)');
    const neg = s.startsWith('-');
    const big = neg ? -BigInt(s.slice(1)) : BigInt(s);
    // Wider than 53 bits goes as a decimal string, as the contract says.
    return big >= BigInt(Number.MIN_SAFE_INTEGER) && big <= BigInt(Number.MAX_SAFE_INTEGER) ? Number(big) : big.toString();
  }
  if (type === 'r32' || type === 'r64') {
    if (/^(nan|inf|-inf)$/i.test(s)) return s.toLowerCase();
    const n = Number(s);
    if (s === '' || !Number.isFinite(n)) throw new Error('expected a number');
    return n;
  }
  // Time types and anything unknown go as typed; the gateway validates.
  return /^-?\d+(\.\d+)?$/.test(s) ? Number(s) : s;
}
