// The WebSocket /api/v1/events: connection, reconnects, and each event into
// the state (rendered by the next tick).

import { retryDelay } from './util.js';
import { state, addEmcy } from './state.js';
import { toast } from './dom.js';
import { api } from './api.js';
import { renderMeta, setBus, setWs } from './header.js';
import { loadNetwork, loadNodes, scheduleNodeRefresh } from './network.js';
import { charts, gatewayTime, onTpdo } from './values.js';
import { onTransfer } from './config.js';

function wsUrl() {
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  // Browsers cannot set headers on a WebSocket, so the token goes in the query.
  const q = state.token ? `?access_token=${encodeURIComponent(state.token)}` : '';
  return `${proto}//${location.host}/api/v1/events${q}`;
}

export function closeWs() {
  if (state.ws) {
    state.ws.onclose = state.ws.onmessage = state.ws.onerror = state.ws.onopen = null;
    try { state.ws.close(); } catch { /* already closed */ }
  }
  state.ws = null;
  state.wsOpen = false;
  setWs('closed', 'offline');
}

let wsTimer = null;
export function connectWs() {
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
