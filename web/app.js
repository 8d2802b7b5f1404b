// Dashboard of canopen-gateway: plain ES modules, no build step.
// Data: REST under /api/v1 for snapshots and commands, the WebSocket
// /api/v1/events for everything live (see ../shared/api-contract.md).
// The DOM is built with textContent only: names and descriptions come from
// EDS files and devices and must never be interpreted as HTML.
//
// This entry module loads the snapshots, starts the event stream, wires the
// panels and redraws what changed. The panels are modules of their own that
// share the one state object of state.js:
//   state.js    the state and the functions that update it
//   api.js      REST with the token, errors as text     auth.js   the token prompt
//   network.js  snapshots (gateway, network, nodes)      events.js the WebSocket events
//   header.js   version, bus, Sparkplug, stream state    nodes.js  nodes table, NMT
//   values.js   the selected node's values and charts    emcy.js   the EMCY list
//   od.js       object dictionary and SDO                lss.js    new devices (LSS)
//   config.js   configuration and maintenance            dcf.js    DCF backup and restore
//   dom.js, format.js, util.js: helpers; charts.js, trace.js: the charts and the bus trace.

import { setupTrace } from './trace.js';
import { state, resetNetwork } from './state.js';
import { $, el, toast, downloadFile } from './dom.js';
import { api, describeError, onUnauthorized } from './api.js';
import { needToken, setupToken } from './auth.js';
import { renderMeta, refreshSparkplug } from './header.js';
import { loadGateway, loadNetwork, loadNodes } from './network.js';
import { connectWs, closeWs } from './events.js';
import { renderNodes, renderAges, selectNode, setupNodes } from './nodes.js';
import { charts, renderValues, setupValues } from './values.js';
import { renderEmcy, setupEmcy } from './emcy.js';
import { renderOd, setupOd } from './od.js';
import { loadLss, setupLss } from './lss.js';
import { renderConfig, setupConfig } from './config.js';
import { setupDcf } from './dcf.js';

const RENDER_INTERVAL_MS = 250; // live values and charts are redrawn at most 4x per second

let loading = null;
async function loadAll() {
  if (loading) return loading;
  loading = (async () => {
    try {
      await loadGateway();
      await Promise.all([loadNetwork(), loadNodes()]);
      state.authBlocked = false;
      if (state.selected === null || !state.nodes.has(state.selected)) {
        const fromHash = Number(new URLSearchParams(location.hash.slice(1)).get('node'));
        const first = state.nodes.has(fromHash) ? fromHash : [...state.nodes.keys()].sort((a, b) => a - b)[0];
        if (first !== undefined) selectNode(first);
      }
      document.body.dataset.loaded = '1';
      connectWs();
      loadLss();
    } catch (e) {
      if (e.status !== 401) toast(describeError(e), 'error');
      if (e.status !== 401) setTimeout(() => { if (!state.wsOpen) loadAll(); }, 3000);
    } finally {
      loading = null;
    }
  })();
  return loading;
}

// The network or the token changed: everything is loaded again.
function restart() {
  closeWs();
  resetNetwork();
  charts.reset();
  if (state.selected !== null) { renderOd(state.selected); renderConfig(state.selected); }
  loadAll();
  trace.restart();
}

function setupEvents() {
  setupConfig();
  setupDcf();
  setupNodes();
  setupValues();
  setupOd();
  setupEmcy();
  setupLss();
  $('#net-select').addEventListener('change', (e) => {
    state.net = Number(e.target.value);
    state.selected = null;
    restart();
  });
}

function tick() {
  if (state.dirty.nodes) { state.dirty.nodes = false; renderNodes(); }
  if (state.dirty.values || state.dirty.valueLayout) { state.dirty.values = false; renderValues(); }
  charts.tick();
  if (state.dirty.emcy) { state.dirty.emcy = false; renderEmcy(); }
}

let trace = null; // the bus trace panel and bus load (trace.js)

function start() {
  onUnauthorized(needToken);
  setupToken(restart);
  setupEvents();
  trace = setupTrace({ $, el, api, toast, downloadFile, net: () => state.net, token: () => state.token,
                       authBlocked: () => state.authBlocked });
  setInterval(tick, RENDER_INTERVAL_MS);
  setInterval(() => { renderAges(); renderMeta(); }, 500);
  // Counters and bus facts are cheap to poll; everything else arrives live.
  setInterval(() => { if (state.wsOpen) loadNetwork().catch(() => {}); }, 10_000);
  // The Sparkplug session has no event of its own: its state is polled.
  setInterval(() => { if (state.wsOpen && state.gateway && state.gateway.sparkplug) refreshSparkplug().catch(() => {}); }, 5_000);
  // The charts scroll even when a node goes quiet, so silence is visible.
  setInterval(() => { if (state.selected !== null) state.dirty.values = true; }, 1000);
  loadAll();
}

start();
