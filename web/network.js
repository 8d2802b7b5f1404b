// Snapshots over REST: the gateway, the network shown and its nodes (with
// their latest values and EMCYs). Everything after them arrives live
// (events.js).

import { state, valuesOf, addEmcy } from './state.js';
import { $, el } from './dom.js';
import { keyOf } from './format.js';
import { api } from './api.js';
import { renderMeta, renderSparkplug, setBus } from './header.js';

export async function loadGateway() {
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

export async function loadNetwork() {
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

export async function loadNodes() {
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

// A node heard for the first time: its details come with the next snapshot.
let nodeRefresh = null;
export function scheduleNodeRefresh() {
  if (nodeRefresh) return;
  nodeRefresh = setTimeout(() => { nodeRefresh = null; loadNodes().catch(() => {}); }, 1500);
}
