// The dashboard's one state object and the functions that update it. The
// other modules import it from here (no globals); what they keep of their
// own (timers, a busy flag) stays private to them.

const TOKEN_KEY = 'canopen-gateway.token';
const EMCY_MAX = 200;

export const state = {
  token: readToken(),
  net: 1,
  networks: [],
  gateway: null,
  gatewayLoadedAt: 0,
  ownId: null,            // the gateway's own node-ID on this network (GET /networks/{net} nodeId)
  ownState: null,         // its NMT state (nodeState)
  nodes: new Map(),       // node-ID -> summary (+ hbAt: client time of the last heartbeat)
  values: new Map(),      // node-ID -> Map("index:sub" -> latest mapped value)
  emcy: [],               // newest first
  selected: null,
  od: new Map(),          // node-ID -> OD response (cached: the EDS does not change at run time)
  ws: null,
  wsOpen: false,
  wsRetry: 0,
  authBlocked: false,     // a 401 happened: wait for a token instead of retrying
  denied: {},             // role -> true once the gateway answered 403 to a request needing it
  dirty: { nodes: false, values: false, emcy: false, valueLayout: false },
};

function readToken() {
  try { return localStorage.getItem(TOKEN_KEY) || ''; } catch { return ''; }
}
function writeToken(t) {
  try {
    if (t) localStorage.setItem(TOKEN_KEY, t); else localStorage.removeItem(TOKEN_KEY);
  } catch { /* storage disabled: the token then lives for this page only */ }
}

// Stores a new token (or '' for none) for this page and this browser.
export function setToken(t) {
  state.token = t;
  writeToken(t);
}

// The latest values of node `id` by "index:sub" (an empty map at first).
export function valuesOf(id) {
  let m = state.values.get(id);
  if (!m) { m = new Map(); state.values.set(id, m); }
  return m;
}

const emcySeen = new Set(); // "node/seq": snapshots after a reconnect repeat what the stream already gave

export function addEmcy(e, live) {
  const id = `${e.node}/${e.seq}`;
  if (emcySeen.has(id)) return;
  emcySeen.add(id);
  const ts = Date.parse(e.timestamp) || Date.now();
  state.emcy.unshift({ ...e, ts, receivedAt: live ? Date.now() : 0 });
  if (state.emcy.length > EMCY_MAX) state.emcy.length = EMCY_MAX;
  if (emcySeen.size > 4 * EMCY_MAX) {
    emcySeen.clear();
    for (const x of state.emcy) emcySeen.add(`${x.node}/${x.seq}`);
  }
  state.dirty.emcy = true;
}

// What belongs to the network shown: forgotten when it or the token changes.
export function resetNetwork() {
  state.authBlocked = false;
  state.nodes.clear();
  state.values.clear();
  state.emcy = [];
  emcySeen.clear();
  state.od.clear();
  state.denied = {};
}
