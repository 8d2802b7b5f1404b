// The header: gateway version and uptime, the CAN bus state, the Sparkplug
// session and the event stream's state.

import { state } from './state.js';
import { $, toast } from './dom.js';
import { fmtDuration } from './format.js';
import { api } from './api.js';

export function renderMeta(status) {
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
export function setBus(s, ev) {
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

// The Sparkplug B edge node's session (GET /gateway `sparkplug`, only when
// it is enabled): born (online) is healthy, waiting for the Primary Host a
// warning, anything else means SCADA sees this gateway as dead.
const SPARKPLUG_LEVEL = { online: 'ok', 'waiting-for-host': 'warn' };

export function renderSparkplug() {
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

export async function refreshSparkplug() {
  const gw = await api('GET', '/gateway');
  if (state.gateway) state.gateway.sparkplug = gw.sparkplug;
  renderSparkplug();
}

export function setWs(st, text) {
  const p = $('#ws-state');
  p.dataset.state = st;
  p.textContent = text;
  document.body.dataset.ws = st;
}
