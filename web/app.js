// Dashboard of canopen-gateway: plain ES module, no build step.
// Data: REST under /api/v1 for snapshots and commands, the WebSocket
// /api/v1/events for everything live (see ../shared/api-contract.md).
// The DOM is built with textContent only: names and descriptions come from
// EDS files and devices and must never be interpreted as HTML.

import { setupTrace } from './trace.js';
import { hex, retryDelay } from './util.js';
import { createCharts, formatScaled } from './charts.js';

const TOKEN_KEY = 'canopen-gateway.token';
const RENDER_INTERVAL_MS = 250; // live values and charts are redrawn at most 4x per second
const EMCY_MAX = 200;

// ---------------------------------------------------------------- state

const state = {
  token: readToken(),
  net: 1,
  networks: [],
  gateway: null,
  gatewayLoadedAt: 0,
  ownId: null,            // the gateway's own node-ID on this network (GET /networks/{net} nodeId)
  ownState: null,         // its NMT state (nodeState)
  nodes: new Map(),       // node-ID -> summary (+ hbAt: client time of the last heartbeat)
  values: new Map(),      // node-ID -> Map("index:sub" -> latest mapped value)
  emcy: [],               // newest first
  selected: null,
  od: new Map(),          // node-ID -> OD response (cached: the EDS does not change at run time)
  ws: null,
  wsOpen: false,
  wsRetry: 0,
  authBlocked: false,     // a 401 happened: wait for a token instead of retrying
  denied: {},             // role -> true once the gateway answered 403 to a request needing it
  dirty: { nodes: false, values: false, emcy: false, valueLayout: false },
};

function readToken() {
  try { return localStorage.getItem(TOKEN_KEY) || ''; } catch { return ''; }
}
function writeToken(t) {
  try {
    if (t) localStorage.setItem(TOKEN_KEY, t); else localStorage.removeItem(TOKEN_KEY);
  } catch { /* storage disabled: the token then lives for this page only */ }
}

// ---------------------------------------------------------------- helpers

const $ = (sel, root = document) => root.querySelector(sel);

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k === 'class') e.className = v;
    else if (k === 'text') e.textContent = v;
    else if (k.startsWith('data-') || k === 'title' || k === 'type' || k === 'role' || k.startsWith('aria-') ||
             k === 'colspan' || k === 'placeholder' || k === 'name' || k === 'value' || k === 'spellcheck' ||
             k === 'tabindex')
      e.setAttribute(k, v === true ? '' : String(v));
    else e[k] = v;
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const keyOf = (index, sub) => `${hex(index, 4)}:${sub}`;

function fmtAge(ms) {
  if (ms === null || ms === undefined || !Number.isFinite(ms)) return '–';
  if (ms < 10_000) return `${(ms / 1000).toFixed(1)} s`;
  if (ms < 120_000) return `${Math.round(ms / 1000)} s`;
  if (ms < 7_200_000) return `${Math.round(ms / 60_000)} min`;
  return `${Math.round(ms / 3_600_000)} h`;
}

function fmtDuration(s) {
  const d = Math.floor(s / 86400), h = Math.floor(s / 3600) % 24, m = Math.floor(s / 60) % 60;
  if (d) return `${d}d ${h}h`;
  if (h) return `${h}h ${m}m`;
  return `${m}m ${Math.floor(s % 60)}s`;
}

function fmtTime(ts) {
  const d = new Date(ts);
  if (Number.isNaN(d.getTime())) return String(ts ?? '');
  return d.toLocaleTimeString(undefined, { hour12: false }) + '.' + String(d.getMilliseconds()).padStart(3, '0');
}

const INT_TYPES = new Set(['i8', 'i16', 'i24', 'i32', 'i40', 'i48', 'i56', 'i64',
                           'u8', 'u16', 'u24', 'u32', 'u40', 'u48', 'u56', 'u64']);
const INT_BITS = (t) => Number(t.slice(1));

// Value as shown: unsigned integers also in hex, because CANopen people read
// status words, codes and identities in hex.
function fmtValue(value, type) {
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
function numeric(value, type) {
  if (typeof value === 'number') return Number.isFinite(value) ? value : null;
  if (typeof value === 'boolean') return value ? 1 : 0;
  if (typeof value === 'string' && type && INT_TYPES.has(type)) {
    const n = Number(value);
    return Number.isFinite(n) ? n : null;
  }
  return null;
}

// Text typed by the user -> JSON value of the contract for `type`.
function parseInput(text, type) {
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

// ---------------------------------------------------------------- REST

class ApiError extends Error {
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
async function api(method, path, body, opts = {}, retried = false) {
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
    if (res.status === 401) needToken(detail);
    throw new ApiError(res.status, detail, data && data.abortCode);
  }
  if (opts.text) return { text, contentType: res.headers.get('Content-Type') || '', data };
  return data;
}

// One readable line per failure; problem+json's detail is the substance.
function describeError(err) {
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

// ---------------------------------------------------------------- toasts

function toast(message, kind = 'info') {
  const t = el('div', { class: 'toast', 'data-kind': kind, role: kind === 'error' ? 'alert' : 'status', text: message });
  t.addEventListener('click', () => t.remove());
  $('#toasts').append(t);
  while ($('#toasts').children.length > 5) $('#toasts').firstElementChild.remove();
  setTimeout(() => t.remove(), kind === 'error' ? 10_000 : 3_500);
}

// ---------------------------------------------------------------- token prompt

function needToken(detail) {
  state.authBlocked = true;
  closeWs();
  setWs('closed', 'token needed');
  if (!state.nodes.size) {
    $('#nodes-body').replaceChildren(el('tr', { class: 'empty' }, el('td', { colspan: 6, text: 'token required' })));
  }
  const msg = state.token
    ? `The gateway refused the stored token (${detail}). Enter a valid token.`
    : 'This gateway requires an access token. Enter it to continue.';
  openTokenDialog(msg, true);
}

function openTokenDialog(message, isError) {
  const box = $('#auth-prompt');
  $('#auth-message').textContent = message;
  $('#auth-message').classList.toggle('err', !!isError);
  box.dataset.reason = isError ? 'required' : 'manual';
  box.hidden = false;
  $('#token-input').value = '';
  $('#token-input').focus();
}

function closeTokenDialog() { $('#auth-prompt').hidden = true; }

function setupToken() {
  $('#token-button').addEventListener('click', () =>
    openTokenDialog(state.token ? 'A token is stored in this browser. Enter another one to replace it.'
                                : 'No token is stored. The gateway may not need one.', false));
  $('#token-cancel').addEventListener('click', closeTokenDialog);
  $('#token-clear').addEventListener('click', () => {
    state.token = '';
    writeToken('');
    closeTokenDialog();
    updateTokenButton();
    restart();
  });
  $('#token-form').addEventListener('submit', (e) => {
    e.preventDefault();
    const t = $('#token-input').value.trim();
    if (!t) { $('#auth-message').textContent = 'Enter a token.'; return; }
    state.token = t;
    writeToken(t);
    closeTokenDialog();
    updateTokenButton();
    restart();
  });
  document.addEventListener('keydown', (e) => {
    if (e.key === 'Escape' && !$('#auth-prompt').hidden) closeTokenDialog();
  });
  updateTokenButton();
}

function updateTokenButton() {
  const b = $('#token-button');
  b.textContent = state.token ? 'Token ✓' : 'Token';
  b.dataset.hasToken = state.token ? '1' : '0';
}

// ---------------------------------------------------------------- loading

async function loadGateway() {
  const gw = await api('GET', '/gateway');
  state.gateway = gw;
  state.gatewayLoadedAt = performance.now();
  state.networks = gw.networks || [];
  if (!state.networks.some((n) => n.network === state.net) && state.networks.length) state.net = state.networks[0].network;
  const net = state.networks.find((n) => n.network === state.net);
  state.ownId = net && net.nodeId !== undefined ? net.nodeId : gw.nodeId ?? null;
  $('#gw-id').textContent = gw.gatewayId || '';
  const sel = $('#net-select');
  sel.replaceChildren(...state.networks.map((n) =>
    el('option', { value: n.network, text: `${n.network}: ${n.interface}`, selected: n.network === state.net })));
  $('#net-select-wrap').hidden = state.networks.length < 2;
  renderMeta();
  renderSparkplug();
}

// The Sparkplug B edge node's session (GET /gateway `sparkplug`, only when
// it is enabled): born (online) is healthy, waiting for the Primary Host a
// warning, anything else means SCADA sees this gateway as dead.
const SPARKPLUG_LEVEL = { online: 'ok', 'waiting-for-host': 'warn' };

function renderSparkplug() {
  const s = state.gateway && state.gateway.sparkplug;
  const p = $('#spb-state');
  p.hidden = !s;
  if (!s) return;
  p.dataset.level = SPARKPLUG_LEVEL[s.state] || 'bad';
  p.dataset.state = `sparkplug-${s.state}`;
  p.textContent = `sparkplug: ${s.state}`;
  const host = s.primaryHost ? `; primary host ${s.primaryHost.id} ${s.primaryHost.online ? 'online' : 'offline'}` : '';
  p.title = `Sparkplug B edge node ${s.groupId}/${s.edgeNodeId}: ${s.state}; bdSeq ${s.bdSeq ?? '–'}; ` +
    `last rebirth ${s.lastRebirth ?? 'none'}${host}; ${s.messagesPublished} messages published`;
}

async function refreshSparkplug() {
  const gw = await api('GET', '/gateway');
  if (state.gateway) state.gateway.sparkplug = gw.sparkplug;
  renderSparkplug();
}

async function loadNetwork() {
  const n = await api('GET', `/networks/${state.net}`);
  setBus(n.bus || 'unknown', n.lastBusEvent);
  state.ownId = n.nodeId;
  state.ownState = n.nodeState || null;
  const own = state.nodes.get(n.nodeId);
  if (own && own.own && state.ownState && own.state !== state.ownState) {
    own.state = state.ownState;
    state.dirty.nodes = true;
  }
  const facts = [
    `${n.simulated ? 'simulated' : n.interface}`,
    n.bitrate ? `${n.bitrate / 1000} kbit/s` : null,
    `gateway node ${n.nodeId}`,
    n.sync && n.sync.producer ? `SYNC ${n.sync.periodUs / 1000} ms` : 'no SYNC',
    n.heartbeatMs ? `heartbeat ${n.heartbeatMs} ms` : null,
    n.counters && n.counters.events !== undefined ? `${n.counters.events} events` : null,
  ].filter(Boolean);
  $('#net-facts').textContent = facts.join(' · ');
}

async function loadNodes() {
  const r = await api('GET', `/networks/${state.net}/nodes`);
  const now = Date.now();
  const seen = new Set();
  for (const n of r.nodes || []) {
    seen.add(n.node);
    const prev = state.nodes.get(n.node);
    state.nodes.set(n.node, {
      ...n,
      own: n.node === state.ownId,
      state: n.node === state.ownId && state.ownState ? state.ownState : n.state,
      hbAt: n.lastHeartbeatAgeMs === null || n.lastHeartbeatAgeMs === undefined ? (prev ? prev.hbAt : null)
                                                                               : now - n.lastHeartbeatAgeMs,
    });
  }
  // The gateway's own node is on the bus too, but the gateway does not hear
  // itself: it is listed only once it sent an EMCY. Shown always, so its
  // dictionary is one click away.
  if (state.ownId !== null && !seen.has(state.ownId)) {
    state.nodes.set(state.ownId, {
      node: state.ownId, name: '', configured: true, state: state.ownState || 'unknown', hbAt: null,
      emcyCount: 0, emcyErrorCount: 0, lastEmcy: null, identity: null, eds: true, own: true, listed: false,
    });
    seen.add(state.ownId);
  }
  for (const id of [...state.nodes.keys()]) if (!seen.has(id)) state.nodes.delete(id);
  state.dirty.nodes = true;
  // Latest TPDO values and EMCY history of every node, so nothing starts
  // empty; a few at a time so a large network stays under the rate limit.
  await inBatches([...state.nodes.keys()], 4, async (id) => {
    try {
      // The own node before it is listed has no node resource (404).
      const unlisted = state.nodes.get(id)?.listed === false;
      const [node, emcy] = await Promise.all([
        unlisted ? { values: [] } : api('GET', `/networks/${state.net}/nodes/${id}`),
        api('GET', `/networks/${state.net}/nodes/${id}/emcy`),
      ]);
      const m = valuesOf(id);
      for (const v of node.values || []) m.set(keyOf(v.index, v.subIndex), v);
      for (const e of emcy.emcy || []) addEmcy({ ...e, node: id }, false);
    } catch (e) {
      if (e.status === 401) throw e;
    }
  });
  state.emcy.sort((a, b) => (b.ts - a.ts));
  state.dirty.values = state.dirty.valueLayout = state.dirty.emcy = true;
}

async function inBatches(items, size, fn) {
  for (let i = 0; i < items.length; i += size) await Promise.all(items.slice(i, i + size).map(fn));
}

function valuesOf(id) {
  let m = state.values.get(id);
  if (!m) { m = new Map(); state.values.set(id, m); }
  return m;
}

let loading = null;
async function loadAll() {
  if (loading) return loading;
  loading = (async () => {
    try {
      await loadGateway();
      await Promise.all([loadNetwork(), loadNodes()]);
      state.authBlocked = false;
      if (state.selected === null || !state.nodes.has(state.selected)) {
        const fromHash = Number(new URLSearchParams(location.hash.slice(1)).get('node'));
        const first = state.nodes.has(fromHash) ? fromHash : [...state.nodes.keys()].sort((a, b) => a - b)[0];
        if (first !== undefined) selectNode(first);
      }
      document.body.dataset.loaded = '1';
      connectWs();
      loadLss();
    } catch (e) {
      if (e.status !== 401) toast(describeError(e), 'error');
      if (e.status !== 401) setTimeout(() => { if (!state.wsOpen) loadAll(); }, 3000);
    } finally {
      loading = null;
    }
  })();
  return loading;
}

function restart() {
  closeWs();
  state.authBlocked = false;
  state.nodes.clear();
  state.values.clear();
  charts.reset();
  state.emcy = [];
  emcySeen.clear();
  state.od.clear();
  state.denied = {};
  if (state.selected !== null) { renderOd(state.selected); renderConfig(state.selected); }
  loadAll();
  trace.restart();
}

// ---------------------------------------------------------------- WebSocket

function wsUrl() {
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  // Browsers cannot set headers on a WebSocket, so the token goes in the query.
  const q = state.token ? `?access_token=${encodeURIComponent(state.token)}` : '';
  return `${proto}//${location.host}/api/v1/events${q}`;
}

function setWs(st, text) {
  const p = $('#ws-state');
  p.dataset.state = st;
  p.textContent = text;
  document.body.dataset.ws = st;
}

function closeWs() {
  if (state.ws) {
    state.ws.onclose = state.ws.onmessage = state.ws.onerror = state.ws.onopen = null;
    try { state.ws.close(); } catch { /* already closed */ }
  }
  state.ws = null;
  state.wsOpen = false;
  setWs('closed', 'offline');
}

let wsTimer = null;
function connectWs() {
  if (state.ws || state.authBlocked) return;
  clearTimeout(wsTimer);
  setWs('connecting', 'connecting…');
  let opened = false;
  const ws = new WebSocket(wsUrl());
  state.ws = ws;
  ws.onopen = () => {
    opened = true;
    state.wsOpen = true;
    // Reconnected after a gap: events were missed, so take a fresh snapshot.
    if (state.wsRetry > 0) { loadNodes().then(() => loadNetwork()).catch(() => {}); charts.refetch(); }
    state.wsRetry = 0;
    ws.send('{}'); // the dashboard wants every network, node and kind
    setWs('open', 'live');
  };
  ws.onmessage = (m) => {
    if (typeof m.data !== 'string') return;
    let msg;
    try { msg = JSON.parse(m.data); } catch { return; }
    if (msg.kind) onEvent(msg);
    else if (msg.error) toast(`Event stream: ${msg.error}`, 'error');
  };
  ws.onclose = async () => {
    state.ws = null;
    state.wsOpen = false;
    if (state.authBlocked) return;
    setWs('closed', 'reconnecting…');
    // A refused upgrade looks like any close to the page: ask REST why, so a
    // missing or wrong token shows the prompt instead of endless retries.
    if (!opened) {
      try { await api('GET', '/gateway'); } catch (e) { if (e.status === 401) return; }
    }
    state.wsRetry++;
    wsTimer = setTimeout(connectWs, retryDelay(state.wsRetry));
  };
}

function onEvent(msg) {
  const ev = msg[msg.kind];
  if (!ev) return;
  if (msg.kind === 'status') { renderMeta(ev); return; }
  if (ev.network !== state.net) return;
  switch (msg.kind) {
    case 'tpdo': onTpdo(ev); break;
    case 'heartbeat': touchNode(ev.node, { state: ev.state, hbAt: Date.now() }); break;
    case 'state':
      // A boot-up starts without the errors the node had (as lastEmcy on the gateway).
      touchNode(ev.node, ev.cause === 'boot-up' ? { state: ev.state, lastEmcy: null } : { state: ev.state });
      charts.stateChanged(ev.node, ev.state, gatewayTime(ev.timestamp));
      break;
    case 'emcy': {
      const n = touchNode(ev.node, {});
      n.emcyCount = (n.emcyCount || 0) + 1;
      if (ev.errorCode !== 0) n.emcyErrorCount = (n.emcyErrorCount || 0) + 1;
      if (!n.lastEmcy || !(n.lastEmcy.seq >= ev.seq)) n.lastEmcy = ev;
      addEmcy(ev, true);
      break;
    }
    case 'bus': setBus(ev.state, ev); break;
    case 'transfer': onTransfer(ev); break;
    case 'boot':
      if (ev.step === 'failed') toast(`Node ${ev.node} boot-up failed: ${ev.error || ev.detail}`, 'error');
      break;
    default: break;
  }
}

function touchNode(id, patch) {
  let n = state.nodes.get(id);
  if (!n) {
    // A node heard for the first time: show it now, details on the next snapshot.
    n = { node: id, name: '', configured: false, state: 'unknown', hbAt: null, emcyCount: 0, emcyErrorCount: 0,
          lastEmcy: null, identity: null, eds: false };
    state.nodes.set(id, n);
    scheduleNodeRefresh();
  }
  const before = n.state;
  Object.assign(n, patch);
  if (patch.state && patch.state !== before) n.changedAt = Date.now();
  state.dirty.nodes = true;
  return n;
}

let nodeRefresh = null;
function scheduleNodeRefresh() {
  if (nodeRefresh) return;
  nodeRefresh = setTimeout(() => { nodeRefresh = null; loadNodes().catch(() => {}); }, 1500);
}

// An event's time (the gateway's clock, as its history uses), unix seconds.
function gatewayTime(ts) {
  const ms = Date.parse(ts);
  return Number.isFinite(ms) ? ms / 1000 : charts.now();
}

function onTpdo(ev) {
  const m = valuesOf(ev.node);
  const t = gatewayTime(ev.timestamp);
  for (const v of ev.values || []) {
    const key = keyOf(v.index, v.subIndex);
    if (!m.has(key)) state.dirty.valueLayout = true;
    m.set(key, { ...v, tpdo: ev.tpdo, timestamp: ev.timestamp });
    const y = numeric(v.value, v.type);
    if (y !== null) charts.sample(ev.node, v.index, v.subIndex, y, t);
  }
  if (ev.node === state.selected) state.dirty.values = true;
}

const emcySeen = new Set(); // "node/seq": snapshots after a reconnect repeat what the stream already gave

function addEmcy(e, live) {
  const id = `${e.node}/${e.seq}`;
  if (emcySeen.has(id)) return;
  emcySeen.add(id);
  const ts = Date.parse(e.timestamp) || Date.now();
  state.emcy.unshift({ ...e, ts, receivedAt: live ? Date.now() : 0 });
  if (state.emcy.length > EMCY_MAX) state.emcy.length = EMCY_MAX;
  if (emcySeen.size > 4 * EMCY_MAX) {
    emcySeen.clear();
    for (const x of state.emcy) emcySeen.add(`${x.node}/${x.seq}`);
  }
  state.dirty.emcy = true;
}

// ---------------------------------------------------------------- rendering: header

function renderMeta(status) {
  const gw = state.gateway;
  if (!gw) return;
  if (status && status.state === 'offline') toast('Gateway reports offline', 'error');
  const up = gw.uptimeSeconds + (performance.now() - state.gatewayLoadedAt) / 1000;
  $('#gw-meta').textContent = `v${gw.version} · up ${fmtDuration(up)}`;
}

// CAN controller states (ISO 11898-1): "error-active" is the normal one,
// whatever its name suggests, so it reads "ok"; the others say what they are.
const BUS = {
  'error-active': { level: 'ok', text: 'ok', hint: 'error-active: the normal state, the controller takes part in all bus traffic' },
  'error-warning': { level: 'warn', text: 'error-warning', hint: 'error counters above 96: errors on the bus (bit rate, termination, wiring?)' },
  'error-passive': { level: 'warn', text: 'error-passive', hint: 'error counters above 127: frequent errors; check bit rate, termination and wiring' },
  'bus-off': { level: 'bad', text: 'bus-off', hint: 'the controller left the bus after too many errors; nothing is sent or received' },
  down: { level: 'bad', text: 'down', hint: 'the CAN interface is down' },
};
function setBus(s, ev) {
  const p = $('#bus-state');
  const b = BUS[s] || { level: 'unknown', text: s, hint: '' };
  p.dataset.state = s;
  p.dataset.level = b.level;
  p.textContent = `bus: ${b.text}`;
  let title = `CAN bus state ${b.hint || s}`;
  if (ev) {
    const tec = ev.tec ?? ev.txErrorCounter, rec = ev.rec ?? ev.rxErrorCounter;
    title += (ev.cause ? ` (last change: ${ev.cause})` : '') +
      (tec !== undefined ? ` · TEC ${tec} REC ${rec}` : '') + (ev.dropped ? ` · ${ev.dropped} frames dropped` : '');
  }
  p.title = title;
}

// ---------------------------------------------------------------- rendering: nodes table

const PROFILES = { 401: 'CiA 401 I/O', 402: 'CiA 402 drive', 404: 'CiA 404 sensor', 406: 'CiA 406 encoder' };

function identityText(id) {
  if (!id) return '';
  const profile = id.deviceType & 0xFFFF;
  return [PROFILES[profile] || (profile ? `profile ${profile}` : null),
          `vendor 0x${hex(id.vendorId, 8)}`, `product 0x${hex(id.productCode, 8)}`,
          `rev 0x${hex(id.revision, 8)}`, id.serial ? `serial ${id.serial}` : null].filter(Boolean).join(' · ');
}

// The node's active error, from its last EMCY since boot-up: an error code
// other than 0000h, or a reset (0000h) whose error register (1001h) says
// other errors remain. null: no error known.
function activeError(n) {
  const e = n && n.lastEmcy;
  if (!e || (e.errorCode === 0 && !e.errorRegister)) return null;
  return e;
}

function errorText(e) {
  const reg = `error register ${hex(e.errorRegister, 2)}h`;
  if (e.errorCode === 0) return `${reg}: errors remain after the last EMCY reset`;
  return `EMCY ${hex(e.errorCode, 4)}h${e.description ? ' ' + e.description : ''} · ${reg}`;
}

function nodeName(n) {
  if (n.own) return n.name || 'this gateway';
  return n.name || (n.configured ? '' : 'not configured');
}

function renderNodes() {
  const body = $('#nodes-body');
  const ids = [...state.nodes.keys()].sort((a, b) => a - b);
  if (!ids.length) {
    body.replaceChildren(el('tr', { class: 'empty' }, el('td', { colspan: 6, text: 'no nodes known on this network' })));
    return;
  }
  const existing = [...body.querySelectorAll('tr[data-node]')].map((r) => Number(r.dataset.node));
  if (existing.join() !== ids.join()) {
    body.replaceChildren(...ids.map((id) => el('tr', { 'data-node': id, tabindex: 0 },
      el('td', { class: 'num mono', 'data-field': 'id', text: id }),
      el('td', { 'data-field': 'name' }),
      el('td', { class: 'col-state' }, el('span', { class: 'pills' },
        el('span', { class: 'pill state', 'data-field': 'state' }),
        el('span', { class: 'pill', 'data-field': 'error', 'data-level': 'bad', text: 'error', hidden: true }))),
      el('td', { class: 'num mono', 'data-field': 'hb-age' }),
      el('td', { class: 'num mono', 'data-field': 'emcy' }),
      el('td', { class: 'col-ident small muted', 'data-field': 'identity' }))));
  }
  for (const id of ids) {
    const n = state.nodes.get(id);
    const row = body.querySelector(`tr[data-node="${id}"]`);
    row.classList.toggle('selected', id === state.selected);
    row.classList.toggle('own', !!n.own);
    setText(row.querySelector('[data-field=name]'), nodeName(n));
    const st = row.querySelector('[data-field=state]');
    setText(st, n.state);
    st.dataset.state = n.state;
    const err = activeError(n);
    const errPill = row.querySelector('[data-field=error]');
    errPill.hidden = !err;
    errPill.title = err ? errorText(err) : '';
    row.dataset.error = err ? '1' : '0';
    // Errors only: an EMCY with code 0000h reports that errors were reset.
    const errors = n.emcyErrorCount ?? 0;
    const count = row.querySelector('[data-field=emcy]');
    setText(count, errors);
    count.classList.toggle('has-emcy', errors > 0);
    count.title = `${errors} EMCY error${errors === 1 ? '' : 's'} and ${Math.max(0, (n.emcyCount ?? 0) - errors)} reset(s) since start`;
    const ident = row.querySelector('[data-field=identity]');
    const identText = n.own ? ownIdentityText() : identityText(n.identity);
    setText(ident, identText || '–');
    ident.title = identText || '';  // the whole text, where the cell cuts it short
  }
  $('#nodes').classList.toggle('no-ident', ids.every((id) => !state.nodes.get(id).identity));
  renderAges();
  if (state.selected !== null) renderNodeHeader();
}

function renderAges() {
  const now = Date.now();
  for (const row of $('#nodes-body').querySelectorAll('tr[data-node]')) {
    const n = state.nodes.get(Number(row.dataset.node));
    if (!n) continue;
    const age = n.hbAt ? now - n.hbAt : null;
    const cell = row.querySelector('[data-field=hb-age]');
    setText(cell, fmtAge(age));
    cell.classList.toggle('stale', age !== null && age > 5000);
  }
}

function setText(node, text) {
  const s = String(text);
  if (node && node.textContent !== s) node.textContent = s;
}

// ---------------------------------------------------------------- rendering: selected node

function selectNode(id) {
  if (state.selected === id) return;
  state.selected = id;
  const params = new URLSearchParams(location.hash.slice(1));
  params.set('node', id);
  history.replaceState(null, '', `#${params}`);
  $('#node-empty').hidden = true;
  $('#node-detail').hidden = false;
  $('#panel-node').dataset.node = id;
  charts.select(id, state.net, !!state.nodes.get(id)?.own);
  state.dirty.nodes = state.dirty.values = state.dirty.valueLayout = state.dirty.emcy = true;
  renderOd(id);
  renderConfig(id);
}

function ownIdentityText() {
  const gw = state.gateway;
  return `the gateway's own node · canopen-gateway${gw && gw.version ? ' v' + gw.version : ''}`;
}

function renderNodeHeader() {
  const n = state.nodes.get(state.selected);
  if (!n) return;
  const name = nodeName(n);
  setText($('#node-title'), `Node ${n.node}${name ? ' · ' + name : ''}`);
  const st = $('#node-state');
  setText(st, n.state);
  st.dataset.state = n.state;
  const err = activeError(n);
  $('#node-error').hidden = !err;
  setText($('#node-error-text'), err ? errorText(err) : '');
  $('#node-error-text').hidden = !err;
  setText($('#node-ident'), n.own ? ownIdentityText()
                                  : identityText(n.identity) || (n.eds ? '' : 'no EDS configured: values are shown raw'));
}

// Charts of the selected node: web/charts.js (server history + live samples).
const charts = createCharts({
  api, el, download: downloadFile,
  nodeState: (id) => state.nodes.get(id)?.state,
  startedAt: () => (state.gateway && Number.isFinite(state.gateway.uptimeSeconds)
    ? (Date.now() - (performance.now() - state.gatewayLoadedAt)) / 1000 - state.gateway.uptimeSeconds : null),
  onChange: () => { state.dirty.values = true; },
});

// The value as shown: in its unit (raw x factor) where the EDS gives one, else raw.
function valueText(id, key, v) {
  return formatScaled(numeric(v.value, v.type), charts.scaleOf(id, key)) ?? fmtValue(v.value, v.type);
}

function renderValues() {
  const id = state.selected;
  const box = $('#values');
  if (id === null) return;
  const m = state.values.get(id) || new Map();
  const keys = [...m.keys()].sort();
  if (state.dirty.valueLayout) {
    charts.destroy();
    if (!keys.length) {
      box.replaceChildren(el('div', { class: 'muted', text: state.nodes.get(id)?.own
        ? 'The gateway\'s own node sends no process data of its own. Its object dictionary is below; ' +
          'reads and writes there are answered by the gateway itself, not over the bus.'
        : 'No TPDO received from this node yet (is it operational?).' }));
    } else {
      box.replaceChildren(...keys.map((k) => {
        const v = m.get(k);
        return el('div', { class: 'value-card', 'data-key': k, 'data-node': id },
          el('div', { class: 'value-head' },
            el('span', { class: 'value-name', title: `${v.name || k} (${v.type}, TPDO${v.tpdo})`, text: v.name || k }),
            el('span', { class: 'value-meta mono', text: k.replace(':', 'h/'),
                         title: `object ${k.replace(':', 'h sub ')}, type ${v.type}, TPDO${v.tpdo}` }),
            el('button', { type: 'button', class: 'btn btn-small btn-ghost chart-csv', 'data-action': 'csv',
                           title: 'Download this chart\'s window as CSV', text: 'CSV' })),
          el('div', { class: 'value-row' },
            el('span', { class: 'value mono', 'data-field': 'value' }),
            el('span', { class: 'value-range mono', 'data-field': 'range', title: 'lowest and highest in the chart' })),
          el('div', { class: 'chart', 'data-field': 'chart', role: 'img' }));
      }));
    }
    state.dirty.valueLayout = false;
  }
  for (const card of box.querySelectorAll('.value-card')) {
    const k = card.dataset.key;
    const v = m.get(k);
    if (!v) continue;
    setText(card.querySelector('[data-field=value]'), valueText(id, k, v));
    charts.draw(card, k);
  }
}

const chartResize = new ResizeObserver(() => charts.resize());

// ---------------------------------------------------------------- rendering: EMCY

function renderEmcy() {
  const onlyNode = $('#emcy-only-node').checked && state.selected !== null;
  const list = onlyNode ? state.emcy.filter((e) => e.node === state.selected) : state.emcy;
  const body = $('#emcy-body');
  if (!list.length) {
    body.replaceChildren(el('tr', { class: 'empty' }, el('td', { colspan: 6, text: 'no EMCY received' })));
    return;
  }
  body.replaceChildren(...list.slice(0, 100).map((e) => el('tr',
    { class: `${e.errorCode === 0 ? 'emcy-reset' : 'emcy-error'}${Date.now() - e.receivedAt < 1500 ? ' emcy-new' : ''}`,
      'data-node': e.node, 'data-code': hex(e.errorCode, 4),
      title: `manufacturer data ${e.manufacturerData || '–'} · seq ${e.seq}` },
    el('td', { class: 'mono small', title: e.timestamp, text: fmtTime(e.timestamp) }),
    el('td', { class: 'num mono', text: e.node }),
    el('td', { class: 'mono', text: `${hex(e.errorCode, 4)}h` }),
    el('td', { class: 'mono', title: 'error register (1001h)', text: `${hex(e.errorRegister, 2)}h` }),
    el('td', { text: e.description || (e.errorCode === 0 ? 'error reset / no error' : '') }),
    el('td', { class: 'col-mfr mono small muted', text: e.manufacturerData || '' }))));
}

// ---------------------------------------------------------------- object dictionary

const WRITABLE = new Set(['rw', 'wo', 'rwr', 'rww']);
const READABLE = new Set(['ro', 'rw', 'rwr', 'rww', 'const']);

async function renderOd(id) {
  const body = $('#od-body');
  const info = $('#od-info');
  body.replaceChildren();
  $('#panel-od').dataset.node = id;
  let od = state.od.get(id);
  if (!od) {
    info.textContent = 'loading…';
    try {
      od = await api('GET', `/networks/${state.net}/nodes/${id}/od`);
      state.od.set(id, od);
      charts.setOd(id, od);
    } catch (e) {
      if (state.selected === id) info.textContent = e.status === 404 ? describeError(e).replace(/^Error 404: /, '') : describeError(e);
      return;
    }
    if (state.selected !== id) return;
  }
  info.textContent = od.gateway
    ? `Node ${id}: the gateway's own node · ${od.productName || 'canopen-gateway'} (built-in dictionary) · ${od.objects.length} objects`
    : `Node ${id}: ${[od.vendorName, od.productName].filter(Boolean).join(' · ')}` +
      `${od.dcf ? ' (DCF)' : ' (EDS)'} · ${od.objects.length} objects`;
  $('#panel-od').dataset.gateway = od.gateway ? '1' : '0';
  const rows = [];
  for (const o of od.objects) {
    const single = o.objectCode === 'VAR' && o.subs.length === 1 && o.subs[0].subIndex === 0;
    if (!single) {
      rows.push(el('tr', { class: 'od-obj', 'data-obj': o.indexHex },
        el('td', { class: 'mono', text: `${o.indexHex}h` }),
        el('td', { colspan: 5, text: o.name, class: 'od-obj-name' })));
    }
    for (const s of o.subs) rows.push(odRow(o, s, single));
  }
  body.replaceChildren(...rows);
  applyOdFilter();
}

function odRow(o, s, single) {
  const key = keyOf(o.index, s.subIndex);
  const canWrite = WRITABLE.has(s.access);
  const canRead = READABLE.has(s.access);
  const range = s.low !== null || s.high !== null ? ` range ${s.low ?? '…'}..${s.high ?? '…'}` : '';
  const title = `default ${s.default ?? '–'}${range}${s.pdoMappable ? ' · PDO-mappable' : ''}`;
  return el('tr', {
    class: single ? 'od-var' : 'od-sub', 'data-od': key, 'data-index': o.index, 'data-sub': s.subIndex,
    'data-type': s.type, 'data-obj': o.indexHex,
    'data-search': `${o.indexHex} ${o.indexHex}h 0x${o.indexHex} ${o.name} ${s.name}`.toLowerCase(),
  },
  el('td', { class: 'mono', text: single ? `${o.indexHex}h` : `  sub ${s.subIndex}` }),
  el('td', { title, text: single ? o.name : s.name }),
  el('td', { class: 'col-type mono small', text: s.type }),
  el('td', { class: 'col-acc mono small', text: s.access }),
  el('td', {}, el('div', { class: 'od-value' },
    el('span', { class: 'mono', 'data-field': 'value' }),
    canWrite ? el('input', { class: 'od-input mono', 'data-field': 'input', 'aria-label': `new value for ${key}`,
                             placeholder: s.default !== null && s.default !== undefined ? String(s.default) : s.type,
                             spellcheck: 'false' }) : null)),
  el('td', { class: 'od-actions' },
    canRead ? el('button', { type: 'button', class: 'btn btn-small', 'data-action': 'read', text: 'Read' }) : null,
    canWrite ? el('button', { type: 'button', class: 'btn btn-small', 'data-action': 'write', text: 'Write' }) : null));
}

function applyOdFilter() {
  const q = $('#od-filter').value.trim().toLowerCase().replace(/^0x/, '').replace(/h$/, '');
  const objMatch = new Set();
  for (const r of $('#od-body').querySelectorAll('tr[data-od]')) {
    const hit = !q || r.dataset.search.includes(q);
    r.hidden = !hit;
    if (hit) objMatch.add(r.dataset.obj);
  }
  for (const r of $('#od-body').querySelectorAll('tr.od-obj')) r.hidden = !objMatch.has(r.dataset.obj);
}

async function sdoAction(row, action) {
  const id = state.selected;
  const index = Number(row.dataset.index);
  const sub = Number(row.dataset.sub);
  const type = row.dataset.type;
  const out = row.querySelector('[data-field=value]');
  const path = `/networks/${state.net}/nodes/${id}/sdo/${hex(index, 4)}/${sub}`;
  row.dataset.status = 'busy';
  out.classList.remove('err');
  try {
    if (action === 'read') {
      const r = await api('GET', path);
      out.textContent = fmtValue(r.value, r.type);
      out.title = `raw ${r.raw || '–'} (${r.type})`;
    } else {
      const input = row.querySelector('[data-field=input]');
      let value;
      try { value = parseInput(input.value, type); } catch (e) { throw new Error(`${hex(index, 4)}h/${sub}: ${e.message}`); }
      await api('PUT', path, { value });
      out.textContent = fmtValue(value, type);
      out.title = 'written';
      toast(`Node ${id} ${hex(index, 4)}h sub ${sub} written`, 'ok');
    }
    row.dataset.status = 'ok';
  } catch (e) {
    row.dataset.status = 'error';
    out.textContent = describeError(e);
    out.classList.add('err');
    if (e.status === 403) toast(describeError(e), 'error');
  }
}

// ---------------------------------------------------------------- NMT

const NMT_TEXT = { start: 'Start', stop: 'Stop', preop: 'Pre-operational', 'reset-node': 'Reset node', 'reset-comm': 'Reset communication' };

// Every command that takes nodes out of operation asks first: on a machine,
// a stopped drive or I/O rack stops the process (CiA 301 7.3.2.2.1). Start
// does not: it is what a node waits for.
const NMT_CONFIRM = {
  stop: { title: (who) => `Stop ${who}?`,
          text: 'A stopped node sends and takes no process data (PDO) and answers no SDO request until it is started again.' },
  preop: { title: (who) => `Switch ${who} to pre-operational?`,
           text: 'A pre-operational node sends and takes no process data (PDO); SDO access stays.' },
  'reset-node': { title: (who) => `Reset ${who}?`,
                  text: 'The node restarts its application: its parameters return to their power-on values, ' +
                        'and it boots again into pre-operational (no process data until started).' },
  'reset-comm': { title: (who) => `Reset the communication of ${who}?`,
                  text: 'The node resets its communication parameters and boots again into pre-operational ' +
                        '(no process data until started).' },
};

function confirmDialog(title, message, okText) {
  const d = $('#confirm');
  setText($('#confirm-title'), title);
  setText($('#confirm-message'), message);
  setText($('#confirm-ok'), okText);
  d.returnValue = '';
  d.showModal();
  $('#confirm-cancel').focus(); // Enter on an unexpected dialog must not stop a machine
  return new Promise((resolve) => d.addEventListener('close', () => resolve(d.returnValue === 'ok'), { once: true }));
}

async function nmt(node, command) {
  const n = state.nodes.get(node);
  const name = n ? nodeName(n) : '';
  const who = node === 0 ? 'all nodes' : `node ${node}${name ? ` (${name})` : ''}`;
  const ask = NMT_CONFIRM[command];
  if (ask) {
    const all = node === 0 ? ` The command goes to every node on network ${state.net}, the gateway's own node included.` : '';
    if (!await confirmDialog(ask.title(who), ask.text + all, NMT_TEXT[command])) return;
  }
  try {
    await api('POST', `/networks/${state.net}/nodes/${node}/nmt`, { command });
    toast(`NMT ${NMT_TEXT[command]} sent to ${who}`, 'ok');
    // The own node's state comes with the network, not as an event.
    if (node === 0 || node === state.ownId) setTimeout(() => loadNetwork().catch(() => {}), 300);
  } catch (e) {
    toast(describeError(e), 'error');
  }
}

// ---------------------------------------------------------------- new devices (LSS)
// Contract "LSS master (CiA 305)": fastscan, the list of what was found,
// configure (node-ID + store) and assign-all. All need an admin token; the
// gateway runs one LSS operation per network at a time.

const lssHex = (n) => '0x' + hex(n, 8);
const lssIdentityText = (id) =>
  `${lssHex(id.vendorId)} ${lssHex(id.productCode)} ${lssHex(id.revisionNumber)} ${lssHex(id.serialNumber)}`;
let lssBusy = false;

function lssErrorText(err) {
  if (!(err instanceof ApiError)) return describeError(err);
  switch (err.status) {
    case 404: return `None: ${err.detail}`;
    case 409: return `Busy: ${err.detail}`;
    case 422: return `The device refused: ${err.detail}`;
    case 504: return `No answer: ${err.detail}`;
    default: return describeError(err);
  }
}

function lssStatus(text, kind) {
  const s = $('#lss-status');
  setText(s, text);
  s.classList.toggle('err', kind === 'error');
}

function renderLss(devices) {
  const body = $('#lss-body');
  if (!devices.length) {
    body.replaceChildren(el('tr', { class: 'empty' }, el('td', { colspan: 3, text: 'no device found' })));
    return;
  }
  body.replaceChildren(...devices.map((d, i) => {
    const input = el('input', { type: 'number', min: 1, max: 127, class: 'lss-id', 'data-field': 'node-id',
                                'aria-label': 'Node-ID to assign', value: d.nodeId ?? '' });
    const row = el('tr', { 'data-lss': i },
      el('td', { class: 'ident', text: lssIdentityText(d.identity) }),
      el('td', { class: 'num' }, d.nodeId != null ? el('span', { text: String(d.nodeId) }) : input),
      el('td', {}, d.nodeId != null ? el('span', { class: 'muted small', text: 'assigned' })
                                    : el('button', { type: 'button', class: 'btn btn-small', 'data-lss-assign': i, text: 'Assign' })));
    row.lssIdentity = d.identity;
    return row;
  }));
}

async function loadLss() {
  try {
    const r = await api('GET', `/networks/${state.net}/lss/devices`);
    renderLss(r.devices || []);
  } catch (e) {
    if (e.status === 403) { lssStatus('Needs an admin token.', 'error'); noteDenied('admin'); }
  }
}

// One LSS request at a time from this page; the buttons say so meanwhile.
async function lssRun(what, fn) {
  if (lssBusy) return;
  lssBusy = true;
  for (const b of document.querySelectorAll('#panel-lss button')) b.disabled = true;
  lssStatus(what);
  try {
    await fn();
  } catch (e) {
    lssStatus(lssErrorText(e), e.status === 404 ? 'info' : 'error');
    if (e.status !== 404) toast(lssErrorText(e), 'error');
  } finally {
    lssBusy = false;
    for (const b of document.querySelectorAll('#panel-lss button')) b.disabled = false;
    await loadLss();
  }
}

function lssScan() {
  return lssRun('Scanning…', async () => {
    const r = await api('POST', `/networks/${state.net}/lss/fastscan`, {});
    lssStatus(`Found ${lssIdentityText(r.identity)}`);
  });
}

function lssAssign(row) {
  const input = row.querySelector('input[data-field=node-id]');
  const nodeId = Number(input.value);
  if (!Number.isInteger(nodeId) || nodeId < 1 || nodeId > 127) {
    lssStatus('Node-ID must be 1..127.', 'error');
    input.focus();
    return;
  }
  return lssRun(`Assigning node-ID ${nodeId}…`, async () => {
    await api('POST', `/networks/${state.net}/lss/configure`, { identity: row.lssIdentity, nodeId, store: true });
    lssStatus(`Node-ID ${nodeId} assigned and stored; the device boots with it.`);
    toast(`LSS: node-ID ${nodeId} assigned`, 'ok');
  });
}

function lssAssignAll() {
  const firstNodeId = Number($('#lss-first').value);
  if (!Number.isInteger(firstNodeId) || firstNodeId < 1 || firstNodeId > 127) {
    lssStatus('First node-ID must be 1..127.', 'error');
    return;
  }
  return lssRun('Assigning all…', async () => {
    const r = await api('POST', `/networks/${state.net}/lss/assign-all`, { firstNodeId, store: true });
    const ids = r.assignments.map((a) => a.nodeId);
    lssStatus(ids.length ? `Assigned node-IDs ${ids.join(', ')} (stored).` : 'No device without a node-ID answered.');
  });
}

// ---------------------------------------------------------------- configuration and maintenance
// Contract "Remote configuration and maintenance": per node its settings
// (GET/PUT config), its EDS (PUT eds), a DCF backup (GET dcf) and restore
// (POST dcf, with a diff against the EDS defaults first), store/restore
// (1010h/1011h) and a CiA 302-3 program download. Long ones report progress
// as `transfer` events (onTransfer). One operation at a time from this page.

const cfg = {
  settings: null,          // the node's settings as GET config answered them
  bootTouched: new Set(),  // boot keys whose checkbox was changed since the last load
  busy: null,              // the running operation's name, or null
  dcf: null,               // {name, text, rows} of the chosen DCF file
};

// What the gateway refused this token (a 403): those buttons are disabled
// until the token changes. The page has no other way to know its role.
function noteDenied(role) {
  state.denied[role] = true;
  if (role === 'operator') state.denied.admin = true;
  updateConfigButtons();
}

// Files (EDS, DCF, program images) go as they are: text/plain would be a
// "simple" cross-site request, which the gateway refuses (415).
const FILE_TYPE = 'application/octet-stream';

const nodePath = (id, rest) => `/networks/${state.net}/nodes/${id}/${rest}`;

function cfgStatus(sel, text, kind = 'info') {
  const s = $(sel);
  setText(s, text);
  s.dataset.kind = kind;
}

function fileOf(sel) {
  const f = $(sel).files;
  return f && f.length ? f[0] : null;
}

function updateConfigButtons() {
  const needs = { '#eds-upload': '#eds-file', '#prog-start': '#prog-file' };
  for (const b of document.querySelectorAll('#panel-config [data-role]')) {
    const role = b.dataset.role;
    const denied = !!state.denied[role];
    const missing = needs[`#${b.id}`] ? !fileOf(needs[`#${b.id}`]) : b.id === 'dcf-apply' ? !cfg.dcf : false;
    b.disabled = denied || missing || cfg.busy !== null;
    b.title = denied ? `Needs a token with the ${role} role` : '';
  }
  $('#dcf-read').disabled = cfg.busy !== null;
}

// Runs one operation for node `id`; its result goes to `statusSel`, or to
// a toast when another node was selected meanwhile.
async function cfgRun(name, id, statusSel, fn) {
  if (cfg.busy) { cfgStatus(statusSel, `Wait: ${cfg.busy} is running.`, 'error'); return; }
  cfg.busy = name;
  updateConfigButtons();
  cfgStatus(statusSel, `${name}…`);
  try {
    const text = await fn();
    if (state.selected === id) cfgStatus(statusSel, text, 'ok');
    else toast(`Node ${id}: ${text}`, 'ok');
  } catch (e) {
    const text = cfgErrorText(e);
    if (e.status === 403 && e.role) noteDenied(e.role);
    if (state.selected === id) cfgStatus(statusSel, text, 'error');
    toast(`Node ${id}: ${text}`, 'error');
  } finally {
    cfg.busy = null;
    updateConfigButtons();
  }
}

function cfgErrorText(err) {
  if (!(err instanceof ApiError)) return describeError(err);
  switch (err.status) {
    case 400: return `Refused: ${err.detail}`;
    case 404: return `Not found: ${err.detail}`;
    case 409: return `Busy: ${err.detail}`;
    case 413: return `Too large: ${err.detail}`;
    default: return describeError(err);
  }
}

// A request that needs `role`: a 403 says this token does not have it.
async function roleApi(role, ...args) {
  try {
    return await api(...args);
  } catch (e) {
    if (e instanceof ApiError && e.status === 403) e.role = role;
    throw e;
  }
}

const SOURCE_TEXT = {
  'state-dir': 'changed at run time, kept in the state directory',
  config: 'from the configuration file',
  none: 'not configured: defaults',
};

function renderConfig(id) {
  const own = state.nodes.get(id)?.own || id === state.ownId;
  setText($('#config-node'), `node ${id}`);
  $('#panel-config').dataset.node = id;
  $('#config-detail').hidden = own;
  $('#config-empty').hidden = !own;
  if (own) {
    setText($('#config-empty'), 'The gateway\'s own node is set up in the gateway\'s configuration file, not here.');
    return;
  }
  for (const sel of ['#eds-file', '#dcf-file', '#prog-file']) $(sel).value = '';
  for (const sel of ['#cfg-status', '#eds-status', '#store-status', '#dcf-status', '#prog-status', '#dcf-text', '#prog-text'])
    cfgStatus(sel, '');
  for (const sel of ['#dcf-bar', '#prog-bar', '#dcf-diff-head', '#dcf-diff-wrap', '#dcf-results-wrap']) $(sel).hidden = true;
  cfg.dcf = null;
  updateConfigButtons();
  loadConfig(id);
}

async function loadConfig(id) {
  cfgStatus('#cfg-status', 'loading…');
  let r;
  try {
    r = await api('GET', nodePath(id, 'config'));
  } catch (e) {
    if (state.selected === id) cfgStatus('#cfg-status', cfgErrorText(e), 'error');
    return;
  }
  if (state.selected !== id) return;
  cfgStatus('#cfg-status', '');
  const settings = r.settings && typeof r.settings === 'object' ? r.settings : {};
  cfg.settings = settings;
  cfg.bootTouched = new Set();
  $('#cfg-source').dataset.source = r.source || '';
  setText($('#cfg-source'), r.source ? `(${SOURCE_TEXT[r.source] || r.source})` : '');
  $('#cfg-source').title = r.file ? `kept in ${r.file}` : '';
  $('#cfg-revert').hidden = r.source !== 'state-dir';
  $('#cfg-name').value = settings.name ?? '';
  setText($('#cfg-file'), settings.dcf ?? settings.eds ?? 'none (values arrive raw)');
  const hb = settings['heartbeat-consumer-ms'];
  $('#cfg-hb').value = hb === undefined || hb === null ? '' : String(hb);
  const g = settings.guarding || {};
  $('#cfg-guard').value = g['guard-time-ms'] ?? '';
  $('#cfg-life').value = g['life-time-factor'] ?? '';
  for (const c of document.querySelectorAll('#cfg-form [data-boot]')) c.checked = !!(settings.boot && settings.boot[c.dataset.boot]);
  $('#cfg-metrics').value = (settings['sparkplug-metrics'] || []).join(', ');
}

// The form as the YAML keys of the node's entry. Keys the form does not
// show (the node's file) go back as they came; empty fields are left out
// (the gateway's default). Values go as typed: the gateway checks them.
function settingsFromForm() {
  const s = { ...(cfg.settings || {}) };
  const put = (k, v) => { if (v === undefined || v === '') delete s[k]; else s[k] = v; };
  put('name', $('#cfg-name').value.trim());
  const hb = $('#cfg-hb').value.trim();
  put('heartbeat-consumer-ms', /^\d+$/.test(hb) ? Number(hb) : hb);
  const guard = $('#cfg-guard').value.trim(), life = $('#cfg-life').value.trim();
  if (guard === '' && life === '') delete s.guarding;
  else s.guarding = { 'guard-time-ms': guard === '' ? 0 : Number(guard), 'life-time-factor': life === '' ? 0 : Number(life) };
  // Only the boot keys the node had or the user changed: an absent key
  // keeps its default (read-pdo-config has no plain false one).
  const boot = { ...(s.boot || {}) };
  for (const c of document.querySelectorAll('#cfg-form [data-boot]')) {
    if (c.dataset.boot in boot || cfg.bootTouched.has(c.dataset.boot)) boot[c.dataset.boot] = c.checked;
  }
  if (Object.keys(boot).length) s.boot = boot;
  const metrics = $('#cfg-metrics').value.split(/[\s,]+/).filter(Boolean);
  put('sparkplug-metrics', metrics.length ? metrics : undefined);
  return s;
}

function saveConfig() {
  const id = state.selected;
  const settings = settingsFromForm();
  return cfgRun('Saving', id, '#cfg-status', async () => {
    await roleApi('admin', 'PUT', nodePath(id, 'config'), settings);
    forgetNode(id);
    await loadConfig(id);
    return 'Saved: in use now and kept across restarts.';
  });
}

// DELETE config: state-dir's settings and file go, the configuration file's apply again.
async function revertConfig() {
  const id = state.selected;
  if (!await confirmDialog(`Revert node ${id} to the configuration file?`,
    'The settings changed at run time and an uploaded EDS/DCF are dropped; the configuration file\'s settings ' +
    'for this node apply again at once (a node only configured at run time is no longer configured).', 'Revert')) return;
  return cfgRun('Reverting', id, '#cfg-status', async () => {
    await roleApi('admin', 'DELETE', nodePath(id, 'config'));
    forgetNode(id);
    await loadConfig(id);
    return 'Reverted: the configuration file\'s settings apply.';
  });
}

// The node's file or name changed: its dictionary and row are loaded again.
function forgetNode(id) {
  state.od.delete(id);
  if (state.selected === id) renderOd(id);
  loadNodes().catch(() => {});
}

function uploadEds() {
  const id = state.selected;
  const file = fileOf('#eds-file');
  if (!file) return;
  return cfgRun(`Uploading ${file.name}`, id, '#eds-status', async () => {
    const text = await file.text();
    const r = await roleApi('admin', 'PUT', `${nodePath(id, 'eds')}?name=${encodeURIComponent(file.name)}`, text,
                            { contentType: FILE_TYPE });
    $('#eds-file').value = '';
    forgetNode(id);
    await loadConfig(id);
    const warnings = (r && r.warnings) || [];
    return `${file.name} accepted and in use (object dictionary reloaded).` +
      (warnings.length ? `\nWarnings:\n${warnings.map((w) => (typeof w === 'string' ? w : w.message || JSON.stringify(w))).join('\n')}` : '');
  });
}

// ---- DCF

function setProgress(bar, label, done, total, unit) {
  bar.hidden = false;
  if (total > 0) {
    bar.max = total;
    bar.value = Math.min(done, total);
    const pct = Math.floor((100 * Math.min(done, total)) / total);
    setText(label, `${done.toLocaleString('en')} / ${total.toLocaleString('en')} ${unit || ''} (${pct} %)`);
  } else {
    bar.removeAttribute('value'); // indeterminate until the first progress
    setText(label, '');
  }
}

function downloadFile(name, text, type = 'text/plain') {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = el('a', { href: url, download: name, hidden: true });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
}

const objText = (index, sub) => `${hex(index, 4)}h sub ${sub}`;

function failedText(list) {
  return list.map((f) => `${objText(f.index, f.subIndex ?? f.sub ?? 0)}: ${f.error || f.detail || 'failed'}` +
                         `${f.abortCode ? ` (${f.abortCode})` : ''}`).join('; ');
}

function readDcf() {
  const id = state.selected;
  setProgress($('#dcf-bar'), $('#dcf-text'), 0, 0);
  return cfgRun('Reading the DCF', id, '#dcf-status', async () => {
    const r = await api('GET', nodePath(id, 'dcf'), undefined, { accept: 'application/json, text/plain;q=0.5', text: true });
    const doc = r.data && typeof r.data === 'object' ? r.data : null;
    const text = doc ? doc.text ?? doc.dcf ?? '' : r.text;
    const name = `node${id}.dcf`;
    downloadFile(name, text);
    const failed = (doc && (doc.failed || doc.failures)) || [];
    const bar = $('#dcf-bar');
    if (bar.max > 1) bar.value = bar.max;
    return `${name} saved${doc && doc.objects !== undefined ? `: ${doc.objects} objects read` : ''}` +
      (failed.length ? `; not readable: ${failedText(failed)}` : '');
  });
}

// A DCF (CiA 306 INI text) as its values: one row per object/sub-object
// with a ParameterValue. Section names carry the sub-index in hex.
function parseDcf(text) {
  const sections = new Map();
  let cur = null;
  for (const line0 of text.split(/\r?\n/)) {
    const line = line0.trim();
    if (!line || line.startsWith(';')) continue;
    const m = /^\[([^\]]+)\]$/.exec(line);
    if (m) { cur = {}; sections.set(m[1].trim().toLowerCase(), cur); continue; }
    const eq = line.indexOf('=');
    if (cur && eq > 0) cur[line.slice(0, eq).trim().toLowerCase()] = line.slice(eq + 1).trim();
  }
  const rows = [];
  for (const [name, keys] of sections) {
    const m = /^([0-9a-f]{4})(?:sub([0-9a-f]{1,2}))?$/.exec(name);
    if (!m || keys.parametervalue === undefined) continue;
    rows.push({ index: parseInt(m[1], 16), sub: m[2] ? parseInt(m[2], 16) : 0,
                name: keys.parametername || '', value: keys.parametervalue });
  }
  return rows.sort((a, b) => a.index - b.index || a.sub - b.sub);
}

// A CiA 306 integer: decimal, 0x hex, leading-0 octal, with $NODEID terms.
function dcfInteger(text, node) {
  let sum = 0n;
  for (const term of text.replace(/\$NODEID/gi, String(node)).split('+')) {
    const t = term.trim();
    if (/^-?0x[0-9a-f]+$/i.test(t)) sum += t.startsWith('-') ? -BigInt(t.slice(1)) : BigInt(t);
    else if (/^0[0-7]+$/.test(t)) sum += BigInt('0o' + t.slice(1));
    else if (/^-?\d+$/.test(t)) sum += BigInt(t);
    else return null;
  }
  return sum;
}

// Both values in one form, so equal values look equal and compare equal.
function dcfCompare(sub, dcfText, node) {
  const type = sub && sub.type;
  const def = sub ? sub.default : undefined;
  if (type && (INT_TYPES.has(type) || type === 'b')) {
    const v = dcfInteger(dcfText, node);
    let d = null;
    try { d = def === null || def === undefined ? null : BigInt(typeof def === 'boolean' ? Number(def) : def); } catch { d = null; }
    const show = (x) => (x === null ? '–' : type === 'b' ? String(x !== 0n) : fmtValue(x.toString(), type));
    return { dcf: v === null ? dcfText : show(v), eds: show(d), same: v !== null && d !== null && v === d };
  }
  if (type === 'r32' || type === 'r64') {
    const v = Number(dcfText), d = Number(def);
    return { dcf: dcfText, eds: def ?? '–', same: Number.isFinite(v) && v === d };
  }
  const norm = (x) => String(x ?? '').replace(/^0x/i, '').replace(/\s+/g, '').toLowerCase();
  const bytes = type === 'os' || type === 'd';
  return { dcf: dcfText, eds: def ?? '–', same: def !== undefined && def !== null &&
           (bytes ? norm(dcfText) === norm(def) : dcfText === String(def)) };
}

async function odOf(id) {
  let od = state.od.get(id);
  if (!od) {
    od = await api('GET', nodePath(id, 'od'));
    state.od.set(id, od);
    charts.setOd(id, od);
  }
  return od;
}

function odEntry(od, index, sub) {
  const o = od && od.objects.find((x) => x.index === index);
  const s = o && o.subs.find((x) => x.subIndex === sub);
  return { obj: o, sub: s, name: o ? (s && s.name && s.name !== o.name ? `${o.name} / ${s.name}` : o.name) : '' };
}

async function chooseDcf() {
  const id = state.selected;
  const file = fileOf('#dcf-file');
  cfg.dcf = null;
  $('#dcf-diff-head').hidden = $('#dcf-diff-wrap').hidden = $('#dcf-results-wrap').hidden = true;
  cfgStatus('#dcf-status', '');
  updateConfigButtons();
  if (!file) return;
  const text = await file.text();
  const rows = parseDcf(text);
  if (!rows.length) {
    cfgStatus('#dcf-status', `${file.name}: no ParameterValue entries: not a DCF of configured values.`, 'error');
    return;
  }
  let od = null;
  try { od = await odOf(id); } catch (e) {
    cfgStatus('#dcf-status', `No EDS defaults to compare with (${cfgErrorText(e)}).`);
  }
  if (state.selected !== id) return;
  const diff = rows.map((r) => {
    const e = odEntry(od, r.index, r.sub);
    const c = dcfCompare(e.sub, r.value, id);
    return { ...r, name: e.name || r.name, eds: e.sub ? c.eds : 'not in the EDS', dcfShown: c.dcf, same: !!e.sub && c.same };
  });
  cfg.dcf = { name: file.name, text, rows: diff };
  renderDcfDiff();
  updateConfigButtons();
}

function renderDcfDiff() {
  const d = cfg.dcf;
  if (!d) return;
  const changed = d.rows.filter((r) => !r.same);
  const all = $('#dcf-diff-all').checked;
  setText($('#dcf-diff-summary'), `${d.name}: ${d.rows.length} values, ${changed.length} differ from the EDS defaults. `);
  $('#dcf-diff-head').hidden = false;
  $('#dcf-diff-wrap').hidden = false;
  const list = all ? d.rows : changed;
  $('#dcf-diff-body').replaceChildren(...(list.length ? list.map((r) => el('tr',
    { 'data-obj': keyOf(r.index, r.sub), 'data-diff': r.same ? '0' : '1' },
    el('td', { text: objText(r.index, r.sub) }),
    el('td', { text: r.name }),
    el('td', { class: 'mono', text: String(r.eds) }),
    el('td', { class: 'mono', text: String(r.dcfShown) })))
    : [el('tr', { class: 'empty' }, el('td', { colspan: 4, text: 'every value equals the EDS default' }))]));
}

async function applyDcf() {
  const id = state.selected;
  const d = cfg.dcf;
  if (!d) return;
  const store = $('#dcf-store').checked, reset = $('#dcf-reset').checked;
  if (reset && !await confirmDialog(`Apply ${d.name} and reset node ${id}?`,
    'The values are written, then the node restarts its application and boots again into pre-operational ' +
    '(no process data until started).', 'Apply and reset')) return;
  setProgress($('#dcf-bar'), $('#dcf-text'), 0, 0);
  $('#dcf-results-wrap').hidden = true;
  return cfgRun(`Applying ${d.name}`, id, '#dcf-status', async () => {
    const q = [store ? 'store=true' : null, reset ? 'reset=true' : null].filter(Boolean).join('&');
    const r = await roleApi('admin', 'POST', `${nodePath(id, 'dcf')}${q ? '?' + q : ''}`, d.text,
                            { contentType: FILE_TYPE });
    const objects = (r && (r.objects || r.results)) || [];
    let od = null;
    try { od = await odOf(id); } catch { od = null; }
    const failed = objects.filter((o) => objectFailed(o));
    if (state.selected === id) {
      $('#dcf-results-body').replaceChildren(...objects.map((o) => {
        const sub = o.subIndex ?? o.sub ?? 0;
        const bad = objectFailed(o);
        return el('tr', { 'data-obj': keyOf(o.index, sub), 'data-result': bad ? 'failed' : 'ok' },
          el('td', { text: objText(o.index, sub) }),
          el('td', { text: odEntry(od, o.index, sub).name }),
          el('td', { text: bad ? `${o.error || o.detail || 'failed'}${o.abortCode ? ` (${o.abortCode})` : ''}` : 'written' }));
      }));
      $('#dcf-results-wrap').hidden = false;
      const bar = $('#dcf-bar');
      if (bar.max > 1) bar.value = bar.max;
    }
    const storeError = r && r.storeError ? `; store failed: ${r.storeError.error || 'failed'}` +
      `${r.storeError.abortCode ? ` (${r.storeError.abortCode})` : ''}` : '';
    const extra = [r && r.stored ? 'stored' : null, r && r.reset ? 'node reset' : null].filter(Boolean).join(', ');
    const text = `${objects.length - failed.length} of ${objects.length} objects written${extra ? ', ' + extra : ''}`;
    if (failed.length || storeError) throw new Error(`${text}${failed.length ? `; ${failed.length} failed (highlighted below)` : ''}${storeError}`);
    return text + '.';
  });
}

const objectFailed = (o) => !!(o.error || o.abortCode) || o.ok === false || o.status === 'failed';

// ---- store / restore

async function storeNode(restore) {
  const id = state.selected;
  if (restore && !await confirmDialog(`Restore the defaults of node ${id}?`,
    'The device loads its default parameters (1011h sub 1 "load") and is reset: it restarts its application ' +
    'and boots into pre-operational (no process data until started). Stored settings are lost.', 'Restore and reset')) return;
  return cfgRun(restore ? 'Restoring' : 'Storing', id, '#store-status', async () => {
    await roleApi('operator', 'POST', nodePath(id, restore ? 'restore' : 'store'));
    return restore ? 'Defaults restored; the node was reset.' : 'Parameters stored in the device (1010h).';
  });
}

// ---- program download (CiA 302-3)

async function downloadProgram() {
  const id = state.selected;
  const file = fileOf('#prog-file');
  const n = Number($('#prog-n').value);
  if (!file) return;
  if (!Number.isInteger(n) || n < 1 || n > 254) { cfgStatus('#prog-status', 'Program number must be 1..254.', 'error'); return; }
  if (!await confirmDialog(`Download ${file.name} to node ${id}?`,
    `The device stops its program (1F51h), program ${n} is cleared and replaced by ${file.name} ` +
    `(${file.size.toLocaleString('en')} bytes), then started. The device does not do its job meanwhile.`, 'Download')) return;
  setProgress($('#prog-bar'), $('#prog-text'), 0, file.size, 'bytes');
  return cfgRun(`Downloading program ${n}`, id, '#prog-status', async () => {
    const image = await file.arrayBuffer();
    const r = await roleApi('admin', 'PUT', nodePath(id, `program/${n}`), image, { contentType: FILE_TYPE });
    const bytes = Number(r && r.bytes !== undefined ? r.bytes : file.size);
    if (state.selected === id) setProgress($('#prog-bar'), $('#prog-text'), bytes, bytes, 'bytes');
    const ident = r && r.identification;
    return `Program ${n}: ${bytes.toLocaleString('en')} bytes downloaded and started; ` +
      (ident === undefined || ident === null ? 'the device has no program identification (1F56h).'
        : `identification ${fmtValue(ident, 'u32')} (1F56h sub ${n}).`);
  });
}

// `transfer` events of the selected node move the bars, whoever started the
// transfer (this page, another client, MQTT).
function onTransfer(ev) {
  if (ev.node !== state.selected) return;
  const program = ev.operation === 'program-download';
  const bar = $(program ? '#prog-bar' : '#dcf-bar');
  setProgress(bar, $(program ? '#prog-text' : '#dcf-text'), Number(ev.done) || 0, Number(ev.total) || 0, ev.unit);
  bar.dataset.status = ev.status;
  if (ev.status === 'failed') {
    cfgStatus(program ? '#prog-status' : '#dcf-status',
      `Failed: ${ev.error || 'transfer failed'}${ev.abortCode ? ` (${ev.abortCode})` : ''}${ev.detail ? ` · ${ev.detail}` : ''}`, 'error');
  }
}

function setupConfig() {
  $('#cfg-form').addEventListener('submit', (e) => { e.preventDefault(); if (state.selected !== null) saveConfig(); });
  $('#cfg-reload').addEventListener('click', () => { if (state.selected !== null) loadConfig(state.selected); });
  $('#cfg-revert').addEventListener('click', revertConfig);
  for (const c of document.querySelectorAll('#cfg-form [data-boot]')) c.addEventListener('change', () => cfg.bootTouched.add(c.dataset.boot));
  $('#eds-file').addEventListener('change', updateConfigButtons);
  $('#prog-file').addEventListener('change', updateConfigButtons);
  $('#eds-upload').addEventListener('click', uploadEds);
  $('#dcf-read').addEventListener('click', readDcf);
  $('#dcf-file').addEventListener('change', chooseDcf);
  $('#dcf-diff-all').addEventListener('change', renderDcfDiff);
  $('#dcf-apply').addEventListener('click', applyDcf);
  $('#node-store').addEventListener('click', () => storeNode(false));
  $('#node-restore').addEventListener('click', () => storeNode(true));
  $('#prog-start').addEventListener('click', downloadProgram);
}

// ---------------------------------------------------------------- wiring

function setupEvents() {
  setupConfig();
  $('#nodes-body').addEventListener('click', (e) => {
    const row = e.target.closest('tr[data-node]');
    if (row) selectNode(Number(row.dataset.node));
  });
  $('#nodes-body').addEventListener('keydown', (e) => {
    const row = e.target.closest('tr[data-node]');
    if (row && (e.key === 'Enter' || e.key === ' ')) { e.preventDefault(); selectNode(Number(row.dataset.node)); }
  });
  $('#panel-node').addEventListener('click', (e) => {
    const b = e.target.closest('button[data-nmt]');
    if (b && state.selected !== null) nmt(state.selected, b.dataset.nmt);
    const csv = e.target.closest('button[data-action=csv]');
    if (csv) {
      const card = csv.closest('.value-card');
      const v = valuesOf(state.selected).get(card.dataset.key);
      charts.csv(card.dataset.key, v && v.name);
    }
  });
  $('#nmt-all').addEventListener('click', (e) => {
    const b = e.target.closest('button[data-nmt-all]');
    if (b) nmt(0, b.dataset.nmtAll);
  });
  $('#od-body').addEventListener('click', (e) => {
    const b = e.target.closest('button[data-action]');
    if (b) sdoAction(b.closest('tr'), b.dataset.action);
  });
  $('#od-body').addEventListener('keydown', (e) => {
    if (e.key === 'Enter' && e.target.matches('input[data-field=input]')) sdoAction(e.target.closest('tr'), 'write');
  });
  let t = null;
  $('#od-filter').addEventListener('input', () => { clearTimeout(t); t = setTimeout(applyOdFilter, 120); });
  $('#emcy-only-node').addEventListener('change', () => { state.dirty.emcy = true; });
  $('#lss-scan').addEventListener('click', lssScan);
  $('#lss-assign-all').addEventListener('click', lssAssignAll);
  $('#lss-body').addEventListener('click', (e) => {
    const b = e.target.closest('button[data-lss-assign]');
    if (b) lssAssign(b.closest('tr'));
  });
  $('#lss-body').addEventListener('keydown', (e) => {
    if (e.key === 'Enter' && e.target.matches('input[data-field=node-id]')) lssAssign(e.target.closest('tr'));
  });
  $('#net-select').addEventListener('change', (e) => {
    state.net = Number(e.target.value);
    state.selected = null;
    restart();
  });
  chartResize.observe($('#values'));
}

function tick() {
  if (state.dirty.nodes) { state.dirty.nodes = false; renderNodes(); }
  if (state.dirty.values || state.dirty.valueLayout) { state.dirty.values = false; renderValues(); }
  charts.tick();
  if (state.dirty.emcy) { state.dirty.emcy = false; renderEmcy(); }
}

let trace = null; // the bus trace panel and bus load (trace.js)

function start() {
  setupToken();
  setupEvents();
  trace = setupTrace({ $, el, api, toast, downloadFile, net: () => state.net, token: () => state.token,
                       authBlocked: () => state.authBlocked });
  setInterval(tick, RENDER_INTERVAL_MS);
  setInterval(() => { renderAges(); renderMeta(); }, 500);
  // Counters and bus facts are cheap to poll; everything else arrives live.
  setInterval(() => { if (state.wsOpen) loadNetwork().catch(() => {}); }, 10_000);
  // The Sparkplug session has no event of its own: its state is polled.
  setInterval(() => { if (state.wsOpen && state.gateway && state.gateway.sparkplug) refreshSparkplug().catch(() => {}); }, 5_000);
  // The charts scroll even when a node goes quiet, so silence is visible.
  setInterval(() => { if (state.selected !== null) state.dirty.values = true; }, 1000);
  loadAll();
}

start();
