// The selected node's process data: value cards with their charts
// (charts.js: server history + live samples), fed by TPDO events.

import { state, valuesOf } from './state.js';
import { $, el, setText, downloadFile } from './dom.js';
import { keyOf, fmtValue, numeric } from './format.js';
import { api } from './api.js';
import { createCharts, formatScaled } from './charts.js';

// Charts of the selected node: web/charts.js (server history + live samples).
export const charts = createCharts({
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

export function renderValues() {
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

// An event's time (the gateway's clock, as its history uses), unix seconds.
export function gatewayTime(ts) {
  const ms = Date.parse(ts);
  return Number.isFinite(ms) ? ms / 1000 : charts.now();
}

export function onTpdo(ev) {
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

export function setupValues() {
  $('#panel-node').addEventListener('click', (e) => {
    const csv = e.target.closest('button[data-action=csv]');
    if (csv) {
      const card = csv.closest('.value-card');
      const v = valuesOf(state.selected).get(card.dataset.key);
      charts.csv(card.dataset.key, v && v.name);
    }
  });
  chartResize.observe($('#values'));
}
