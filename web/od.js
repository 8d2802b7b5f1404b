// The selected node's object dictionary (from its EDS, cached) with SDO
// read and write per entry.

import { hex } from './util.js';
import { state } from './state.js';
import { $, el, toast } from './dom.js';
import { keyOf, fmtValue, parseInput } from './format.js';
import { api, describeError } from './api.js';
import { charts } from './values.js';

const WRITABLE = new Set(['rw', 'wo', 'rwr', 'rww']);
const READABLE = new Set(['ro', 'rw', 'rwr', 'rww', 'const']);

export async function renderOd(id) {
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

// The node's dictionary, from the cache or the gateway.
export async function odOf(id) {
  let od = state.od.get(id);
  if (!od) {
    od = await api('GET', `/networks/${state.net}/nodes/${id}/od`);
    state.od.set(id, od);
    charts.setOd(id, od);
  }
  return od;
}

export function setupOd() {
  $('#od-body').addEventListener('click', (e) => {
    const b = e.target.closest('button[data-action]');
    if (b) sdoAction(b.closest('tr'), b.dataset.action);
  });
  $('#od-body').addEventListener('keydown', (e) => {
    if (e.key === 'Enter' && e.target.matches('input[data-field=input]')) sdoAction(e.target.closest('tr'), 'write');
  });
  let t = null;
  $('#od-filter').addEventListener('input', () => { clearTimeout(t); t = setTimeout(applyOdFilter, 120); });
}
