// REST requests under /api/v1 with the stored token, and their errors as
// readable text.

import { state } from './state.js';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// Called with the gateway's detail when it answers 401 (the token prompt).
let unauthorized = () => {};
export function onUnauthorized(fn) { unauthorized = fn; }

export class ApiError extends Error {
  constructor(status, detail, abortCode) {
    super(detail);
    this.status = status;
    this.detail = detail;
    this.abortCode = abortCode;
  }
}

// body: a JSON value, or with opts.contentType a file's content (string,
// ArrayBuffer) sent as it is. opts.accept: the Accept header; opts.text: answer
// {text, contentType, data} (data: the JSON, if the answer is JSON) instead of the JSON.
export async function api(method, path, body, opts = {}, retried = false) {
  const headers = { Accept: opts.accept || 'application/json' };
  if (state.token) headers.Authorization = `Bearer ${state.token}`;
  const raw = opts.contentType !== undefined;
  if (body !== undefined) headers['Content-Type'] = raw ? opts.contentType : 'application/json';
  let res;
  try {
    res = await fetch(`/api/v1${path}`, {
      method, headers, cache: 'no-store', body: body === undefined ? undefined : raw ? body : JSON.stringify(body),
    });
  } catch (e) {
    throw new ApiError(0, `gateway unreachable (${e.message})`);
  }
  const text = await res.text();
  let data = null;
  if (text) { try { data = JSON.parse(text); } catch { data = null; } }
  // The gateway rate-limits per client; a read can simply wait its turn once.
  if (res.status === 429 && method === 'GET' && !retried) {
    await sleep(1000 * Math.min(5, Number(res.headers.get('Retry-After')) || 1));
    return api(method, path, body, opts, true);
  }
  if (!res.ok) {
    const detail = (data && (data.detail || data.title)) || res.statusText || `HTTP ${res.status}`;
    if (res.status === 401) unauthorized(detail);
    throw new ApiError(res.status, detail, data && data.abortCode);
  }
  if (opts.text) return { text, contentType: res.headers.get('Content-Type') || '', data };
  return data;
}

// One readable line per failure; problem+json's detail is the substance.
export function describeError(err) {
  if (!(err instanceof ApiError)) return String(err && err.message || err);
  switch (err.status) {
    case 0: return err.detail;
    case 401: return `Token required or invalid: ${err.detail}`;
    case 403: return `Not permitted for this token's role: ${err.detail}`;
    case 422: return `SDO abort${err.abortCode ? ' ' + err.abortCode : ''}: ${err.detail}`;
    case 429: return `Gateway busy, try again: ${err.detail}`;
    case 503: return `Bus unavailable: ${err.detail}`;
    case 504: return `No answer from the node: ${err.detail}`;
    default: return `Error ${err.status}: ${err.detail}`;
  }
}

// A request that needs `role`: a 403 says this token does not have it.
export async function roleApi(role, ...args) {
  try {
    return await api(...args);
  } catch (e) {
    if (e instanceof ApiError && e.status === 403) e.role = role;
    throw e;
  }
}
