// The nodes table, the selected node's header and NMT commands.

import { hex } from './util.js';
import { state } from './state.js';
import { $, el, setText, toast, confirmDialog } from './dom.js';
import { fmtAge } from './format.js';
import { api, describeError } from './api.js';
import { loadNetwork } from './network.js';
import { charts } from './values.js';
import { renderOd } from './od.js';
import { renderConfig } from './config.js';

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

export function renderNodes() {
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

export function renderAges() {
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

export function selectNode(id) {
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

export function setupNodes() {
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
  });
  $('#nmt-all').addEventListener('click', (e) => {
    const b = e.target.closest('button[data-nmt-all]');
    if (b) nmt(0, b.dataset.nmtAll);
  });
}
