// Process-data charts of the dashboard's selected node (issue 18 item 3).
//
// What is drawn per object: the gateway's history of it
// (GET /networks/{net}/nodes/{node}/history?window=S, docs/reference/rest.md)
// plus the TPDO samples the event stream brings after that, bucketed the same
// way (mean, min, max per bucket of `resolution` seconds) so a reload shows
// what the live page showed. A null bucket is a break (the node left
// Operational or was lost): the line stops there instead of pretending the
// value held. Values are raw in memory and scaled (raw x factor, in unit)
// only for display and export.
//
// Not thread-related; everything runs on the page's one event loop. The
// caller (app.js) MUST call sample() for TPDO values, stateChanged() for NMT
// state events, and draw() from its render tick; nothing here touches the
// DOM outside the value cards and the node panel's window selector.

import { hex, csvField } from './util.js';

export const WINDOWS = [[60, '1 min'], [600, '10 min'], [3600, '1 h'], [21600, '6 h'], [86400, '24 h']];
export const DEFAULT_WINDOW = 600;
// Live buckets kept per object. Live samples are bucketed, so a fast PDO adds
// at most one entry per bucket: 24 h at 60 s is 1440, plus room for breaks.
export const HISTORY_MAX = 1600;
const WINDOW_KEY = 'canopen-gateway.chart-window';
const CHART_HEIGHT = 150;
const REFETCH_S = 300;          // the server's view replaces the live one now and then (missed events, reconnects)

const TIME_INCRS = [1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 10800, 21600, 43200, 86400];

export const resolutionOf = (w) => (w <= 600 ? 1 : w <= 3600 ? 10 : 60);

const keyOf = (index, sub) => `${hex(index, 4)}:${sub}`;

// ---------------------------------------------------------------- units

// {unit, factor} -> the value in unit, or null when it cannot be scaled.
function scaled(raw, s) {
  if (raw === null || raw === undefined) return null;
  const n = typeof raw === 'number' ? raw : typeof raw === 'boolean' ? (raw ? 1 : 0) : Number(raw);
  if (!Number.isFinite(n)) return null;
  return s && s.factor != null ? n * s.factor : n;
}

// Enough digits for a sensor, none of the float noise of raw x 0.1.
const tidy = (n) => (Number.isInteger(n) ? String(n) : String(Number(n.toPrecision(6))));

// "12.3 mV" for a value with a unit or factor; null when the object has
// neither (the caller shows the raw value as before).
export function formatScaled(raw, scale) {
  if (!scale || (!scale.unit && scale.factor == null)) return null;
  const v = scaled(raw, scale);
  if (v === null) return null;
  return scale.unit ? `${tidy(v)} ${scale.unit}` : tidy(v);
}

// ---------------------------------------------------------------- model

// One object of one node: server buckets (arrays as the reply has them) and
// live buckets after them ({x, b, n, sum, min, max}; n = 0 is a break).
function newSeries() {
  return { server: null, live: [] };
}

// startedAt(): when the gateway started, unix seconds on the browser's clock
// (null if not known): its history cannot reach further back.
export function createCharts({ api, el, download, nodeState, startedAt, onChange }) {
  const series = new Map();   // "node/IIII:s" -> series
  const scales = new Map();   // "node/IIII:s" -> {unit, factor, name} (history reply first, then the OD)
  const plots = new Map();    // "IIII:s" of the selected node -> {u, res, holder}
  let node = null;
  let net = 1;
  let windowS = initialWindow();
  let res = resolutionOf(windowS);
  let offset = 0;             // gateway clock - browser clock, seconds (from the history reply)
  let status = { state: 'idle', text: '' };
  let generation = 0;
  let fetchedAt = 0;
  let skipHistory = false;    // the selected node sends no process data

  const now = () => Date.now() / 1000 + offset;
  const sk = (n, key) => `${n}/${key}`;

  function initialWindow() {
    const fromHash = Number(new URLSearchParams(location.hash.slice(1)).get('w'));
    if (WINDOWS.some(([w]) => w === fromHash)) return fromHash;
    let stored = NaN;
    try { stored = Number(localStorage.getItem(WINDOW_KEY)); } catch { /* storage off */ }
    return WINDOWS.some(([w]) => w === stored) ? stored : DEFAULT_WINDOW;
  }

  function rememberWindow() {
    const params = new URLSearchParams(location.hash.slice(1));
    params.set('w', windowS);
    history.replaceState(null, '', `#${params}`);
    try { localStorage.setItem(WINDOW_KEY, String(windowS)); } catch { /* storage off */ }
  }

  function get(n, key) {
    let s = series.get(sk(n, key));
    if (!s) { s = newSeries(); series.set(sk(n, key), s); }
    return s;
  }

  // Live buckets at a coarser resolution: merged; at a finer one they cannot
  // be split, so they go (the refetch that follows fills the window).
  function rebucket(from, to) {
    for (const s of series.values()) {
      if (to < from || to % from) { s.live = []; continue; }
      const out = [];
      for (const e of s.live) {
        const last = out[out.length - 1];
        if (e.n === 0) { if (!last || last.n !== 0) out.push({ ...e }); continue; }
        const b = Math.floor(e.b / to) * to;
        if (last && last.n > 0 && last.b === b) {
          last.n += e.n; last.sum += e.sum;
          last.min = Math.min(last.min, e.min); last.max = Math.max(last.max, e.max);
        } else out.push({ ...e, b, x: last && last.x >= b ? last.x + 0.001 : b });
      }
      s.live = out;
    }
  }

  // A TPDO value of any node (t: the gateway's receive time, unix seconds).
  function sample(n, index, sub, raw, t) {
    const y = scaled(raw, null);
    if (y === null) return;
    const s = get(n, keyOf(index, sub));
    const live = s.live;
    const b = Math.floor(t / res) * res;
    const last = live[live.length - 1];
    if (last && last.n > 0 && last.b === b) {
      last.n++; last.sum += y;
      if (y < last.min) last.min = y;
      if (y > last.max) last.max = y;
    } else {
      // After a break inside the same bucket the new bucket sits just after
      // the break, so x stays ascending.
      const x = last && last.x >= b ? last.x + 0.001 : b;
      live.push({ x, b, n: 1, sum: y, min: y, max: y });
      if (live.length > HISTORY_MAX) live.splice(0, live.length - HISTORY_MAX);
    }
  }

  // A node left Operational or was lost: every object of it gets a break now.
  function brk(n, t) {
    const prefix = `${n}/`;
    for (const [k, s] of series) {
      if (!k.startsWith(prefix)) continue;
      const last = s.live[s.live.length - 1];
      if (last ? last.n === 0 : !s.server || s.server.mean[s.server.mean.length - 1] === null) continue;
      const x = last && last.x >= t ? last.x + 0.001 : t;
      s.live.push({ x, b: Math.floor(t / res) * res, n: 0, sum: 0, min: 0, max: 0 });
      if (s.live.length > HISTORY_MAX) s.live.splice(0, s.live.length - HISTORY_MAX);
    }
    if (n === node) onChange();
  }

  function stateChanged(n, st, t) {
    if (st !== 'operational') brk(n, t ?? now());
  }

  // ------------------------------------------------------------ server history

  async function fetchHistory() {
    if (node === null || skipHistory) return;
    const gen = ++generation;
    const n = node, w = windowS;
    status = { state: 'loading', text: 'loading history…' };
    onChange();
    const asked = Date.now() / 1000;
    let r;
    try {
      r = await api('GET', `/networks/${net}/nodes/${n}/history?window=${w}`);
    } catch (e) {
      if (gen !== generation) return;
      fetchedAt = Date.now();
      status = { state: 'error', text: `no history from the gateway (${e.detail || e.message}): live samples since this page opened` };
      onChange();
      return;
    }
    if (gen !== generation) return;
    fetchedAt = Date.now();
    const to = Date.parse(r.to) / 1000;
    if (Number.isFinite(to)) offset = to - (asked + Date.now() / 1000) / 2;
    const step = r.resolution || res;
    const cut = Number.isFinite(to) ? Math.floor(to / step) * step : -Infinity;
    const seen = new Set();
    for (const s of r.series || []) {
      const key = keyOf(s.index, s.sub);
      seen.add(key);
      const ser = get(n, key);
      ser.server = { t: s.t || [], mean: s.mean || [], min: s.min || [], max: s.max || [], res: step };
      // The reply covers everything before its last (partial) bucket.
      ser.live = ser.live.filter((e) => e.x >= cut);
      const sc = scales.get(sk(n, key)) || {};
      scales.set(sk(n, key), { unit: s.unit ?? sc.unit ?? null, factor: s.factor ?? sc.factor ?? null,
                               name: s.name || sc.name || '' });
    }
    for (const [k, ser] of series) if (k.startsWith(`${n}/`) && !seen.has(k.slice(k.indexOf('/') + 1))) ser.server = null;
    const mem = r.memory;
    status = { state: 'ok', text: mem ? `history: ${(mem.bytes / 1048576).toFixed(1)} of ${(mem.maxBytes / 1048576).toFixed(0)} MiB` +
      `${mem.refusedObjects ? `, ${mem.refusedObjects} objects refused (memory cap)` : ''}` : '' };
    onChange();
  }

  // Units of a node's objects from its dictionary (GET .../od sub-entries).
  function setOd(n, od) {
    for (const o of (od && od.objects) || []) {
      for (const s of o.subs || []) {
        if (s.unit == null && s.factor == null) continue;
        const k = sk(n, keyOf(o.index, s.subIndex));
        const sc = scales.get(k) || {};
        scales.set(k, { unit: sc.unit ?? s.unit ?? null, factor: sc.factor ?? s.factor ?? null, name: sc.name || s.name || '' });
      }
    }
    if (n === node) onChange();
  }

  const scaleOf = (n, key) => scales.get(sk(n, key)) || null;

  // ------------------------------------------------------------ what is drawn

  // The series of one object in the window: x (unix s), mean/min/max raw,
  // null at breaks. hold: extend the last value to now (an operational node's
  // event-driven TPDO holds), never across a break.
  function points(n, key, hold) {
    const s = series.get(sk(n, key));
    const out = { x: [], mean: [], min: [], max: [], real: 0 };
    if (!s) return out;
    const t0 = now() - windowS;
    const liveStart = s.live.length ? s.live[0].x : Infinity;
    const push = (x, mean, lo, hi) => {
      // One point before the window keeps the line entering from the left edge.
      if (x < t0) { out.x[0] = x; out.mean[0] = mean; out.min[0] = lo; out.max[0] = hi; return; }
      out.x.push(x); out.mean.push(mean); out.min.push(lo); out.max.push(hi);
    };
    if (s.server) {
      const v = s.server;
      for (let i = 0; i < v.t.length && v.t[i] < liveStart; i++) push(v.t[i], v.mean[i], v.min[i], v.max[i]);
    }
    for (const e of s.live) {
      if (e.n === 0) push(e.x, null, null, null);
      else push(e.x, e.sum / e.n, e.min, e.max);
    }
    out.real = out.x.length;
    const last = out.x.length - 1;
    const t = now();
    if (hold && last >= 0 && out.mean[last] !== null && t > out.x[last]) {
      out.x.push(t); out.mean.push(out.mean[last]); out.min.push(out.min[last]); out.max.push(out.max[last]);
    }
    return out;
  }

  function cssVar(name, fallback) {
    return getComputedStyle(document.documentElement).getPropertyValue(name).trim() || fallback;
  }

  // Tick labels in the browser's local time; seconds only where they matter.
  function timeTicks(u, splits, _axis, _space, incr) {
    const day = (t) => new Date(t * 1000).toDateString();
    const opts = { hour: '2-digit', minute: '2-digit', hour12: false };
    if (incr < 60) opts.second = '2-digit';
    const labels = splits.map((t, i) => {
      const d = new Date(t * 1000);
      const hm = d.toLocaleTimeString(undefined, opts);
      return i > 0 && day(t) !== day(splits[i - 1])
        ? `${d.toLocaleDateString(undefined, { month: 'short', day: 'numeric' })} ${hm}` : hm;
    });
    u.root.parentElement.dataset.xTicks = labels.join('|');
    return labels;
  }

  function valueTicks(u, splits) {
    const labels = splits.map((v) => (v === null ? '' : tidy(Number(v.toPrecision(6)))));
    u.root.parentElement.dataset.yTicks = labels.join('|');
    return labels;
  }

  function makePlot(holder, key, scale, withBand) {
    if (!window.uPlot) return null; // vendor script missing: values still show, just no chart
    const stroke = cssVar('--accent', '#1f6feb');
    const muted = cssVar('--muted', '#5f6b7a');
    const line = cssVar('--line', '#dde3ea');
    const axis = { stroke: muted, grid: { stroke: line, width: 1 }, ticks: { stroke: line, width: 1 },
                   font: '11px system-ui, sans-serif', labelFont: '11px system-ui, sans-serif' };
    const s = [{}, { label: 'mean', stroke, width: 1.5, spanGaps: false, points: { show: false } }];
    const opts = {
      width: Math.max(160, holder.clientWidth), height: CHART_HEIGHT, class: 'chart-plot',
      cursor: { show: false }, legend: { show: false }, select: { show: false },
      scales: {
        x: { time: true },
        // 8% headroom so extremes and flat lines stay visible inside the box.
        y: { range: (u, min, max) => {
          if (min === null || max === null) return [0, 1];
          const pad = min === max ? Math.max(1, Math.abs(min) * 0.1) : (max - min) * 0.08;
          return [min - pad, max + pad];
        } },
      },
      axes: [
        // Whole seconds and up: sub-second ticks would repeat the same label.
        { ...axis, values: timeTicks, space: 60, incrs: TIME_INCRS },
        { ...axis, values: valueTicks, size: 52, label: scale && scale.unit ? scale.unit : undefined, labelSize: 16 },
      ],
      series: s,
    };
    if (withBand) {
      const faint = cssVar('--accent-fill', 'rgba(31,111,235,.12)');
      s.push({ label: 'min', stroke: faint, width: 1, spanGaps: false, points: { show: false } },
             { label: 'max', stroke: faint, width: 1, spanGaps: false, points: { show: false } });
      opts.bands = [{ series: [3, 2], fill: faint }];
    }
    return new window.uPlot(opts, withBand ? [[], [], [], []] : [[], []], holder);
  }

  // Draws one value card's chart; `card` holds [data-field=chart].
  function draw(card, key) {
    const holder = card.querySelector('[data-field=chart]');
    if (!holder || node === null) return;
    const scale = scaleOf(node, key);
    const unit = scale && scale.unit ? scale.unit : '';
    const band = res > 1;
    let p = plots.get(key);
    if (p && (p.holder !== holder || p.band !== band || p.unit !== unit)) { p.u.destroy(); plots.delete(key); p = null; }
    const pts = points(node, key, nodeState(node) === 'operational');
    holder.dataset.window = windowS;
    holder.dataset.resolution = res;
    holder.dataset.points = pts.real;
    let gaps = 0;
    // A break counts once the line had a value before it (a break before any
    // value, such as the boot-up at start, is nothing a reader can see).
    for (let i = 1; i < pts.real; i++) if (pts.mean[i] === null && pts.mean[i - 1] !== null) gaps++;
    holder.dataset.gaps = gaps;
    holder.dataset.unit = unit;
    holder.setAttribute('aria-label', `${scale?.name || key}${unit ? ' in ' + unit : ''}, last ${labelOf(windowS)}` +
      `${gaps ? `, ${gaps} break${gaps > 1 ? 's' : ''}` : ''}`);
    if (!pts.x.length) return;
    if (!p) {
      const u = makePlot(holder, key, scale, band);
      if (!u) return;
      p = { u, holder, band, unit };
      plots.set(key, p);
    }
    const f = (arr) => arr.map((v) => scaled(v, scale));
    const mean = f(pts.mean);
    p.u.setData(band ? [pts.x, mean, f(pts.min), f(pts.max)] : [pts.x, mean], false);
    const t = now();
    const s = series.get(sk(node, key));
    // The window, but not before there can be data (the gateway's start, or
    // the first sample without its history), so a young chart is not a sliver
    // at the right edge; at least a minute, or the window if shorter.
    const began = s && s.server ? (startedAt() ?? -Infinity) + offset : pts.x.length ? pts.x[0] : -Infinity;
    p.u.setScale('x', { min: Math.min(t - Math.min(60, windowS), Math.max(t - windowS, began)), max: t });
    let lo = Infinity, hi = -Infinity;
    for (let i = 0; i < pts.real; i++) {
      const v = mean[i];
      if (v !== null && pts.x[i] >= t - windowS) { if (v < lo) lo = v; if (v > hi) hi = v; }
    }
    const range = card.querySelector('[data-field=range]');
    if (range) {
      const txt = lo < hi ? `${tidy(Number(lo.toPrecision(4)))} … ${tidy(Number(hi.toPrecision(4)))}${unit ? ' ' + unit : ''}` : '';
      if (range.textContent !== txt) range.textContent = txt;
    }
  }

  function destroy() {
    for (const p of plots.values()) p.u.destroy();
    plots.clear();
  }

  function resize() {
    for (const p of plots.values()) {
      const w = p.holder.clientWidth;
      if (w && Math.abs(w - p.u.width) > 2) p.u.setSize({ width: w, height: CHART_HEIGHT });
    }
  }

  // ------------------------------------------------------------ CSV


  function csv(key, name) {
    const scale = scaleOf(node, key);
    const pts = points(node, key, false);
    const t0 = now() - windowS;
    const band = res > 1;
    const title = `${name || scale?.name || key}${scale?.unit ? ` [${scale.unit}]` : ''}`;
    const rows = [band ? `time,${csvField(title)},min,max` : `time,${csvField(title)}`];
    const num = (v) => { const y = scaled(v, scale); return y === null ? '' : tidy(y); };
    for (let i = 0; i < pts.real; i++) {
      if (pts.x[i] < t0) continue;
      const time = new Date(Math.round(pts.x[i] * 1000)).toISOString();
      rows.push(band ? `${time},${num(pts.mean[i])},${num(pts.min[i])},${num(pts.max[i])}` : `${time},${num(pts.mean[i])}`);
    }
    const [index, sub] = key.split(':');
    const file = `net${net}-node${node}-${index}_${hex(Number(sub), 2)}-${windowS}.csv`;
    download(file, rows.join('\r\n') + '\r\n', 'text/csv');
    return file;
  }

  // ------------------------------------------------------------ selection and window

  const labelOf = (w) => (WINDOWS.find(([x]) => x === w) || [w, `${w} s`])[1];

  function renderSelector() {
    const box = document.querySelector('#chart-window');
    if (!box) return;
    if (!box.children.length) {
      box.replaceChildren(...WINDOWS.map(([w, label]) => el('button',
        { type: 'button', class: 'btn btn-small', 'data-window': w, text: label, title: `last ${label}` })));
      box.addEventListener('click', (e) => {
        const b = e.target.closest('button[data-window]');
        if (b) setWindow(Number(b.dataset.window));
      });
    }
    for (const b of box.children) b.setAttribute('aria-pressed', String(Number(b.dataset.window) === windowS));
  }

  function renderStatus() {
    const note = document.querySelector('#chart-note');
    if (!note) return;
    if (note.textContent !== status.text) note.textContent = status.text;
    note.dataset.state = status.state;
  }

  function setWindow(w) {
    if (!WINDOWS.some(([x]) => x === w) || w === windowS) return;
    const before = res;
    windowS = w;
    res = resolutionOf(w);
    if (res !== before) { rebucket(before, res); destroy(); }
    rememberWindow();
    renderSelector();
    onChange();
    fetchHistory();
  }

  // noHistory: the node sends no process data (the gateway's own node), so
  // there is nothing to ask the gateway for.
  function select(n, network, noHistory = false) {
    net = network;
    if (n === node) return;
    destroy();
    // Only the selected node keeps the gateway's buckets (up to 1440 per
    // object); another node's are fetched again when it is selected.
    for (const ser of series.values()) ser.server = null;
    node = n;
    renderSelector();
    status = { state: 'idle', text: '' };
    generation++;
    skipHistory = noHistory;
    fetchHistory();
  }

  function reset() {
    destroy();
    series.clear();
    scales.clear();
    node = null;
    generation++;
  }

  // Called from the render tick: the status line, and a refetch now and then.
  function tick() {
    renderStatus();
    if (node !== null && fetchedAt && status.state !== 'idle' && Date.now() - fetchedAt > REFETCH_S * 1000 && status.state !== 'loading') {
      fetchedAt = Date.now();
      fetchHistory();
    }
  }

  return {
    sample, stateChanged, setOd, scaleOf, draw, destroy, resize, csv, select, reset, tick,
    refetch: fetchHistory, now,
    get window() { return windowS; },
    get resolution() { return res; },
  };
}
