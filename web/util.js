// Small helpers the dashboard's modules share (charts.js and trace.js among them).

// 0x1A -> "001A" with `digits` hex digits, upper case.
export const hex = (n, digits) => Number(n).toString(16).toUpperCase().padStart(digits, '0');

// One CSV field (RFC 4180): quoted when it holds a quote, comma or line
// break; null and undefined are empty.
export const csvField = (v) => {
  const s = v === undefined || v === null ? '' : String(v);
  return /[",\n\r]/.test(s) ? `"${s.replaceAll('"', '""')}"` : s;
};

// Milliseconds before reconnect attempt `retry` of a WebSocket: 1 s, 2 s,
// 4 s ... up to 10 s.
export const retryDelay = (retry) => Math.min(10_000, 500 * 2 ** Math.min(retry, 5));
