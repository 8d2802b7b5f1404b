// The EMCY list: every node's, or the selected node's only.

import { hex } from './util.js';
import { state } from './state.js';
import { $, el } from './dom.js';
import { fmtTime } from './format.js';

export function renderEmcy() {
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

export function setupEmcy() {
  $('#emcy-only-node').addEventListener('change', () => { state.dirty.emcy = true; });
}
