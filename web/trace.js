// Bus trace view and bus load of the dashboard (the "Bus trace" panel and
// the bus load under the network facts). Plain ES module, imported by app.js.
//
// Trace: the WebSocket GET /api/v1/networks/{net}/trace (docs/reference/
// websocket.md "Bus trace"), open only while the user has the view live and
// the page is visible, so an idle dashboard costs the gateway nothing. The
// COB-ID filter goes to the gateway (less traffic); node and service are
// filtered here from the message's `node` and `service` fields.
// Bus load: GET /api/v1/networks/{net} `busLoad`, polled every 2 s while the
// page is visible.
//
// The DOM is built with textContent only (decoded texts come from the bus).

import { csvField, hex, retryDelay } from './util.js';

const BUFFER_MAX = 10_000;  // frames kept for the view and the exports; the oldest go first
const ROWS_MAX = 500;       // table rows in the DOM; older ones are removed
const LOAD_POLL_MS = 2000;
const LOAD_KEEP_S = 600;    // bus load history kept for the chart (10 min)

export const SERVICES = {
  nmt: 'NMT', sync: 'SYNC', time: 'TIME', emcy: 'EMCY', tpdo: 'TPDO', rpdo: 'RPDO', sdo: 'SDO',
  'error-control': 'Heartbeat / error control', lss: 'LSS', other: 'other',
};

// The service column: short names; the token stays in the row's data-service.
const SERVICE_SHORT = { 'error-control': 'err. control' };
const serviceText = (svc) => SERVICE_SHORT[svc] || (svc === 'other' ? 'other' : svc.toUpperCase());

const pad = (n, w = 2) => String(n).padStart(w, '0');
const hexId = (f) => hex(f.id, f.ext ? 8 : 3);
const dlcOf = (f) => (f.rtr ? 'R' : String(f.data.length / 2));

// "1A0-1FF, 701" (hex COB-IDs, optional 0x or h) -> [[416, 511], [1793, 1793]];
// throws with a readable reason.
export function parseIdRanges(text) {
  const out = [];
  for (const part of text.split(/[,\s]+/).filter(Boolean)) {
    const m = /^(?:0x)?([0-9a-f]{1,8})h?(?:-(?:0x)?([0-9a-f]{1,8})h?)?$/i.exec(part);
    if (!m) throw new Error(`"${part}" is not a hex COB-ID or range like 180-1FF`);
    const from = parseInt(m[1], 16), to = m[2] !== undefined ? parseInt(m[2], 16) : from;
    if (from > to) throw new Error(`${part}: the range must go upwards`);
    if (to > 0x1FFFFFFF) throw new Error(`${part}: at most 1FFFFFFF`);
    out.push([from, to]);
  }
  if (out.length > 64) throw new Error('at most 64 ranges');
  return out;
}

// The capture's candump -L line (gateway/trace/capture.cpp candump_line with
// canopen::can::to_string): "(1700000000.123456) can0 185#0A0B". The trace
// message has no DLC for remote frames nor the FD BRS/ESI bits, so those are
// written as "R" and flags 4 (FD only).
export function candumpLine(f, iface) {
  let frame = `${hexId(f)}#`;
  if (f.rtr) frame += 'R';
  else frame += (f.fd ? '#4' : '') + f.data.toUpperCase();
  return `(${f.sec}.${f.usec}) ${iface} ${frame}`;
}

// Fixed-size ring of the newest frames: a push is O(1) at any frame rate.
class Ring {
  constructor(size) { this.size = size; this.clear(); }
  clear() { this.items = new Array(this.size); this.start = 0; this.length = 0; }
  push(x) {
    this.items[(this.start + this.length) % this.size] = x;
    if (this.length < this.size) this.length++; else this.start = (this.start + 1) % this.size;
  }
  at(i) { return this.items[(this.start + i) % this.size]; } // 0 = oldest
  filter(fn) { const out = []; for (let i = 0; i < this.length; i++) if (fn(this.at(i))) out.push(this.at(i)); return out; }
}

export function csvLine(f) {
  return [f.t, f.dir, hexId(f), f.node ?? '', f.service, dlcOf(f), f.data.toUpperCase(), f.decoded].map(csvField).join(',');
}

// A trace message -> the frame the view keeps. t: "2026-11-24T17:46:31.123456Z".
function toFrame(m) {
  const ms = Date.parse(m.t.replace(/(\.\d{3})\d*Z$/, '$1Z')); // ms precision is all Date has
  const frac = (/\.(\d+)Z$/.exec(m.t) || [, '0'])[1];
  return {
    t: m.t, ms, sec: String(Math.floor(ms / 1000)).padStart(10, '0'), usec: frac.padEnd(6, '0').slice(0, 6),
    id: m.id, ext: !!m.ext, rtr: !!m.rtr, fd: !!m.fd, dir: m.dir, data: m.data || '',
    decoded: m.decoded || '', service: m.service || 'other', node: m.node,
  };
}

function localTime(ms) {
  const d = new Date(ms);
  return `${pad(d.getHours())}:${pad(d.getMinutes())}:${pad(d.getSeconds())}.${pad(d.getMilliseconds(), 3)}`;
}

const stamp = () => new Date().toISOString().replace(/[-:]/g, '').replace(/\.\d+Z$/, 'Z');

// ctx: { $, el, api, toast, downloadFile, net(): number, token(): string,
//        authBlocked(): bool }
export function setupTrace(ctx) {
  const { $, el } = ctx;
  const t = {
    live: false,       // the user wants the trace (Start)
    paused: false,
    ws: null, opened: false, retry: 0, timer: null,
    buffer: new Ring(BUFFER_MAX), // the newest frames, for the table and the exports
    pending: [],       // matching frames not yet in the table
    received: 0, lost: 0,
    ids: [],           // COB-ID ranges in force ([] = all)
    node: null, service: '',
    iface: 'can',
    raf: 0,
  };
  const body = $('#trace-body');
  const scroller = $('#trace-scroll');

  const matches = (f) =>
    (t.node === null || f.node === t.node) && (!t.service || f.service === t.service) &&
    (t.ids.length === 0 || t.ids.some(([a, b]) => f.id >= a && f.id <= b));

  function setState(st, text) {
    const p = $('#trace-state');
    p.dataset.state = st;
    p.textContent = text;
  }

  function renderCounts() {
    const c = $('#trace-counts');
    const shown = body.querySelectorAll('tr[data-id]').length;
    c.dataset.received = t.received;
    c.dataset.shown = shown;
    c.dataset.lost = t.lost;
    c.textContent = `received ${t.received} · shown ${shown}${t.paused ? ' (paused)' : ''} · lost ${t.lost}` +
      ` · buffer ${t.buffer.length}/${BUFFER_MAX}`;
    c.title = 'received: frames since Start (also while paused); shown: rows in the table (the newest ' +
      `${ROWS_MAX} matching); lost: frames the gateway could not send this view in time; ` +
      'buffer: the frames the exports save (filters applied)';
  }

  function row(f) {
    return el('tr', { 'data-id': f.id, 'data-node': f.node ?? '', 'data-service': f.service, 'data-dir': f.dir },
      el('td', { text: localTime(f.ms), title: f.t }),
      el('td', { text: f.dir }),
      el('td', { class: 'num', text: hexId(f) }),
      el('td', { class: 'num', text: f.node ?? '' }),
      el('td', { text: serviceText(f.service), title: SERVICES[f.service] }),
      el('td', { class: 'num', text: dlcOf(f) }),
      el('td', { class: 'trace-data', text: f.data.toUpperCase().replace(/(..)(?=.)/g, '$1 ') }),
      el('td', { text: f.decoded }));
  }

  const atBottom = () => scroller.scrollTop + scroller.clientHeight >= scroller.scrollHeight - 4;

  // New rows once per animation frame, appended; never a rebuild per frame.
  function flush() {
    t.raf = 0;
    if (t.paused) { renderCounts(); return; }
    const follow = atBottom();
    const batch = t.pending.length > ROWS_MAX ? t.pending.slice(-ROWS_MAX) : t.pending;
    t.pending = [];
    if (batch.length) {
      body.querySelector('tr.empty')?.remove();
      const frag = document.createDocumentFragment();
      for (const f of batch) frag.append(row(f));
      body.append(frag);
      let extra = body.children.length - ROWS_MAX;
      while (extra-- > 0) body.firstElementChild.remove();
      if (follow) scroller.scrollTop = scroller.scrollHeight;
    }
    renderCounts();
  }
  const schedule = () => { if (!t.raf) t.raf = requestAnimationFrame(flush); };

  // The table from the buffer: after a filter change, a resume or a clear.
  function rebuild() {
    t.pending = [];
    const rows = [];
    for (let i = t.buffer.length - 1; i >= 0 && rows.length < ROWS_MAX; i--) if (matches(t.buffer.at(i))) rows.push(t.buffer.at(i));
    rows.reverse();
    if (rows.length) body.replaceChildren(...rows.map(row));
    else body.replaceChildren(el('tr', { class: 'empty' }, el('td', { colspan: 8, text: t.live ? 'no frames yet' : 'press Start to see the bus' })));
    scroller.scrollTop = scroller.scrollHeight;
    renderCounts();
  }

  function onFrame(m) {
    const f = toFrame(m);
    t.received++;
    t.buffer.push(f);
    if (!t.paused && matches(f)) {
      t.pending.push(f);
      if (t.pending.length > ROWS_MAX * 2) t.pending.splice(0, t.pending.length - ROWS_MAX);
    }
    schedule();
  }

  function sendFilter() {
    if (t.ws && t.opened) t.ws.send(JSON.stringify(t.ids.length ? { ids: t.ids } : {}));
  }

  function url() {
    const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
    // Browsers cannot set headers on a WebSocket, so the token goes in the query.
    const q = ctx.token() ? `?access_token=${encodeURIComponent(ctx.token())}` : '';
    return `${proto}//${location.host}/api/v1/networks/${ctx.net()}/trace${q}`;
  }

  function close() {
    clearTimeout(t.timer);
    if (t.ws) {
      t.ws.onclose = t.ws.onmessage = t.ws.onerror = t.ws.onopen = null;
      try { t.ws.close(); } catch { /* already closed */ }
    }
    t.ws = null;
    t.opened = false;
  }

  const wanted = () => t.live && document.visibilityState === 'visible' && !ctx.authBlocked();

  function connect() {
    if (t.ws || !wanted()) return;
    clearTimeout(t.timer);
    setState('connecting', 'connecting…');
    let opened = false;
    const ws = new WebSocket(url());
    t.ws = ws;
    ws.onopen = () => {
      opened = t.opened = true;
      t.retry = 0;
      sendFilter();
      setState('open', 'live');
      rebuild();
    };
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') return;
      let m;
      try { m = JSON.parse(e.data); } catch { return; }
      if (m.id !== undefined && m.t) onFrame(m);
      else if (m.lost !== undefined) { t.lost += m.lost; schedule(); }
      else if (m.error) idsError(`Refused by the gateway: ${m.error.detail || m.error.title || 'bad filter'}`);
    };
    ws.onclose = async () => {
      t.ws = null;
      t.opened = false;
      if (!wanted()) { setState('closed', 'off'); return; }
      setState('closed', 'reconnecting…');
      // A refused upgrade (401, 503 with 8 trace clients) looks like any close:
      // ask REST so a missing token shows the prompt instead of endless retries.
      if (!opened) {
        try { await ctx.api('GET', `/networks/${ctx.net()}`); } catch (err) {
          if (err.status === 401) { setState('closed', 'token needed'); return; }
        }
      }
      t.retry++;
      t.timer = setTimeout(connect, retryDelay(t.retry));
    };
  }

  function setLive(on) {
    t.live = on;
    const b = $('#trace-live');
    b.textContent = on ? 'Stop' : 'Start';
    b.setAttribute('aria-pressed', on ? 'true' : 'false');
    $('#trace-pause').disabled = !on;
    if (on) {
      t.received = 0;
      t.lost = 0;
      t.retry = 0;
      connect();
    } else {
      close();
      setState('closed', 'off');
      setPaused(false);
    }
    renderCounts();
  }

  function setPaused(on) {
    t.paused = on;
    const b = $('#trace-pause');
    b.textContent = on ? 'Resume' : 'Pause';
    b.setAttribute('aria-pressed', on ? 'true' : 'false');
    $('#panel-trace').dataset.paused = on ? '1' : '0';
    if (!on) rebuild(); // the latest frames, not where it stopped
    renderCounts();
  }

  function idsError(text) {
    const e = $('#trace-ids-error');
    e.hidden = !text;
    e.textContent = text || '';
    $('#trace-ids').setAttribute('aria-invalid', text ? 'true' : 'false');
  }

  function applyFilters() {
    const n = $('#trace-node').value.trim();
    const node = n === '' ? null : Number(n);
    if (node !== null && !(Number.isInteger(node) && node >= 1 && node <= 127)) {
      $('#trace-node').setAttribute('aria-invalid', 'true');
      return;
    }
    $('#trace-node').setAttribute('aria-invalid', 'false');
    let ids;
    try { ids = parseIdRanges($('#trace-ids').value); } catch (err) { idsError(err.message); return; }
    idsError('');
    const idsChanged = JSON.stringify(ids) !== JSON.stringify(t.ids);
    t.node = node;
    t.service = $('#trace-service').value;
    t.ids = ids;
    if (idsChanged) sendFilter();
    rebuild();
  }

  function exportFrames(kind) {
    const frames = t.buffer.filter(matches);
    if (!frames.length) { ctx.toast('No frames to export: start the trace (or loosen the filters) first.', 'error'); return; }
    const name = `canopen-net${ctx.net()}-trace-${stamp()}`;
    if (kind === 'candump') {
      ctx.downloadFile(`${name}.log`, frames.map((f) => candumpLine(f, t.iface)).join('\n') + '\n');
    } else {
      const head = 'time,dir,id,node,service,dlc,data,decoded';
      ctx.downloadFile(`${name}.csv`, [head, ...frames.map(csvLine)].join('\r\n') + '\r\n');
    }
  }

  // ---- bus load

  const load = { t: [], p1: [], p10: [], chart: null, timer: null };

  function loadChart() {
    if (load.chart || !window.uPlot) return load.chart;
    const box = $('#bus-load-chart');
    const css = (n, d) => getComputedStyle(document.documentElement).getPropertyValue(n).trim() || d;
    const axis = { stroke: css('--muted', '#666'), grid: { stroke: css('--line', '#ddd'), width: 1 },
                   ticks: { stroke: css('--line', '#ddd') }, font: '11px system-ui, sans-serif', size: 30 };
    load.chart = new window.uPlot({
      width: Math.max(200, box.clientWidth || 300), height: 110, class: 'bus-load-plot',
      legend: { show: false }, cursor: { show: true, x: true, y: false }, select: { show: false },
      // The x scale is set to the last LOAD_KEEP_S seconds on each update (showLoad).
      scales: { x: { time: true }, y: { range: (u, min, max) => [0, Math.max(5, Math.ceil((max || 0) * 1.2))] } },
      axes: [{ ...axis }, { ...axis, size: 50, values: (u, v) => v.map((x) => `${x} %`) }],
      series: [{}, { label: '1 s', stroke: css('--accent', '#1f6feb'), width: 1.5, fill: css('--accent-fill', 'rgba(31,111,235,.12)') },
               { label: '10 s', stroke: css('--muted', '#888'), width: 1, dash: [4, 3] }],
    }, [[], [], []], box);
    new ResizeObserver(() => load.chart.setSize({ width: Math.max(200, box.clientWidth), height: 110 })).observe(box);
    return load.chart;
  }

  function showLoad(n) {
    const b = n && n.busLoad;
    const p = $('#bus-load');
    const p1 = b && typeof b.percent1s === 'number' ? b.percent1s : null;
    const p10 = b && typeof b.percent10s === 'number' ? b.percent10s : null;
    t.iface = n && n.simulated ? `demo${ctx.net()}` : (n && n.interface) || 'can'; // as the capture names it
    if (p1 === null) {
      p.textContent = 'bus load –';
      p.dataset.state = 'none';
      p.title = (b && b.reason) || 'no bus load reported yet';
    } else {
      p.textContent = `bus load ${p1.toFixed(1)} %` + (p10 !== null ? ` (10 s: ${p10.toFixed(1)} %)` : '');
      p.dataset.state = 'ok';
      p.title = `Share of the ${b.bitrate / 1000} kbit/s bus busy with frames (stuffing estimated), over 1 s and 10 s`;
    }
    $('#bus-load-chart').hidden = p1 === null && load.t.length === 0;
    if (p1 === null && !(b && b.bitrate)) return; // nothing to chart without a bitrate
    const now = Date.now() / 1000;
    load.t.push(now); load.p1.push(p1); load.p10.push(p10);
    while (load.t.length && load.t[0] < now - LOAD_KEEP_S) { load.t.shift(); load.p1.shift(); load.p10.shift(); }
    const c = loadChart();
    if (c) {
      // A fixed window: the first points do not stretch over the whole width.
      c.setData([load.t, load.p1, load.p10], false);
      c.setScale('x', { min: now - LOAD_KEEP_S, max: now });
    }
  }

  async function pollLoad() {
    if (document.visibilityState !== 'visible' || ctx.authBlocked()) return;
    try { showLoad(await ctx.api('GET', `/networks/${ctx.net()}`)); } catch { /* shown by the app's own loads */ }
  }

  // ---- wiring

  $('#trace-live').addEventListener('click', () => setLive(!t.live));
  $('#trace-pause').addEventListener('click', () => setPaused(!t.paused));
  $('#trace-clear').addEventListener('click', () => { t.buffer.clear(); t.received = 0; t.lost = 0; rebuild(); });
  $('#trace-export-candump').addEventListener('click', () => exportFrames('candump'));
  $('#trace-export-csv').addEventListener('click', () => exportFrames('csv'));
  $('#trace-service').replaceChildren(el('option', { value: '', text: 'all' }),
    ...Object.entries(SERVICES).map(([v, text]) => el('option', { value: v, text })));
  let debounce = null;
  const later = () => { clearTimeout(debounce); debounce = setTimeout(applyFilters, 250); };
  $('#trace-node').addEventListener('input', later);
  $('#trace-ids').addEventListener('input', later);
  $('#trace-service').addEventListener('change', applyFilters);
  document.addEventListener('visibilitychange', () => {
    if (document.visibilityState === 'visible') { connect(); pollLoad(); } else { close(); setState('closed', t.live ? 'hidden: off' : 'off'); }
  });
  load.timer = setInterval(pollLoad, LOAD_POLL_MS);
  rebuild();

  return {
    // The network changed (or the token): a new trace and a new bus load history.
    restart() {
      close();
      t.buffer.clear(); t.pending = []; t.received = 0; t.lost = 0;
      load.t = []; load.p1 = []; load.p10 = [];
      if (load.chart) load.chart.setData([[], [], []]);
      rebuild();
      connect();
      pollLoad();
    },
  };
}
