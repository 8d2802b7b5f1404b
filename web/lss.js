// New devices (LSS).
// Contract "LSS master (CiA 305)": fastscan, the list of what was found,
// configure (node-ID + store) and assign-all. All need an admin token; the
// gateway runs one LSS operation per network at a time.

import { hex } from './util.js';
import { state } from './state.js';
import { $, el, setText, toast } from './dom.js';
import { api, ApiError, describeError } from './api.js';
import { noteDenied } from './config.js';

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

export async function loadLss() {
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

export function setupLss() {
  $('#lss-scan').addEventListener('click', lssScan);
  $('#lss-assign-all').addEventListener('click', lssAssignAll);
  $('#lss-body').addEventListener('click', (e) => {
    const b = e.target.closest('button[data-lss-assign]');
    if (b) lssAssign(b.closest('tr'));
  });
  $('#lss-body').addEventListener('keydown', (e) => {
    if (e.key === 'Enter' && e.target.matches('input[data-field=node-id]')) lssAssign(e.target.closest('tr'));
  });
}
