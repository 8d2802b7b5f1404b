// Configuration and maintenance of the selected node (the DCF part: dcf.js).
// Contract "Remote configuration and maintenance": per node its settings
// (GET/PUT config), its EDS (PUT eds), a DCF backup (GET dcf) and restore
// (POST dcf, with a diff against the EDS defaults first), store/restore
// (1010h/1011h) and a CiA 302-3 program download. Long ones report progress
// as `transfer` events (onTransfer). One operation at a time from this page.

import { state } from './state.js';
import { $, setText, toast, confirmDialog } from './dom.js';
import { fmtValue } from './format.js';
import { api, roleApi, ApiError, describeError } from './api.js';
import { loadNodes } from './network.js';
import { renderOd } from './od.js';

export const cfg = {
  settings: null,          // the node's settings as GET config answered them
  bootTouched: new Set(),  // boot keys whose checkbox was changed since the last load
  busy: null,              // the running operation's name, or null
  dcf: null,               // {name, text, rows} of the chosen DCF file
};

// What the gateway refused this token (a 403): those buttons are disabled
// until the token changes. The page has no other way to know its role.
export function noteDenied(role) {
  state.denied[role] = true;
  if (role === 'operator') state.denied.admin = true;
  updateConfigButtons();
}

// Files (EDS, DCF, program images) go as they are: text/plain would be a
// "simple" cross-site request, which the gateway refuses (415).
export const FILE_TYPE = 'application/octet-stream';

export const nodePath = (id, rest) => `/networks/${state.net}/nodes/${id}/${rest}`;

export function cfgStatus(sel, text, kind = 'info') {
  const s = $(sel);
  setText(s, text);
  s.dataset.kind = kind;
}

export function fileOf(sel) {
  const f = $(sel).files;
  return f && f.length ? f[0] : null;
}

export function updateConfigButtons() {
  const needs = { '#eds-upload': '#eds-file', '#prog-start': '#prog-file' };
  for (const b of document.querySelectorAll('#panel-config [data-role]')) {
    const role = b.dataset.role;
    const denied = !!state.denied[role];
    const missing = needs[`#${b.id}`] ? !fileOf(needs[`#${b.id}`]) : b.id === 'dcf-apply' ? !cfg.dcf : false;
    b.disabled = denied || missing || cfg.busy !== null;
    b.title = denied ? `Needs a token with the ${role} role` : '';
  }
  $('#dcf-read').disabled = cfg.busy !== null;
}

// Runs one operation for node `id`; its result goes to `statusSel`, or to
// a toast when another node was selected meanwhile.
export async function cfgRun(name, id, statusSel, fn) {
  if (cfg.busy) { cfgStatus(statusSel, `Wait: ${cfg.busy} is running.`, 'error'); return; }
  cfg.busy = name;
  updateConfigButtons();
  cfgStatus(statusSel, `${name}…`);
  try {
    const text = await fn();
    if (state.selected === id) cfgStatus(statusSel, text, 'ok');
    else toast(`Node ${id}: ${text}`, 'ok');
  } catch (e) {
    const text = cfgErrorText(e);
    if (e.status === 403 && e.role) noteDenied(e.role);
    if (state.selected === id) cfgStatus(statusSel, text, 'error');
    toast(`Node ${id}: ${text}`, 'error');
  } finally {
    cfg.busy = null;
    updateConfigButtons();
  }
}

export function cfgErrorText(err) {
  if (!(err instanceof ApiError)) return describeError(err);
  switch (err.status) {
    case 400: return `Refused: ${err.detail}`;
    case 404: return `Not found: ${err.detail}`;
    case 409: return `Busy: ${err.detail}`;
    case 413: return `Too large: ${err.detail}`;
    default: return describeError(err);
  }
}

const SOURCE_TEXT = {
  'state-dir': 'changed at run time, kept in the state directory',
  config: 'from the configuration file',
  none: 'not configured: defaults',
};

export function renderConfig(id) {
  const own = state.nodes.get(id)?.own || id === state.ownId;
  setText($('#config-node'), `node ${id}`);
  $('#panel-config').dataset.node = id;
  $('#config-detail').hidden = own;
  $('#config-empty').hidden = !own;
  if (own) {
    setText($('#config-empty'), 'The gateway\'s own node is set up in the gateway\'s configuration file, not here.');
    return;
  }
  for (const sel of ['#eds-file', '#dcf-file', '#prog-file']) $(sel).value = '';
  for (const sel of ['#cfg-status', '#eds-status', '#store-status', '#dcf-status', '#prog-status', '#dcf-text', '#prog-text'])
    cfgStatus(sel, '');
  for (const sel of ['#dcf-bar', '#prog-bar', '#dcf-diff-head', '#dcf-diff-wrap', '#dcf-results-wrap']) $(sel).hidden = true;
  cfg.dcf = null;
  updateConfigButtons();
  loadConfig(id);
}

async function loadConfig(id) {
  cfgStatus('#cfg-status', 'loading…');
  let r;
  try {
    r = await api('GET', nodePath(id, 'config'));
  } catch (e) {
    if (state.selected === id) cfgStatus('#cfg-status', cfgErrorText(e), 'error');
    return;
  }
  if (state.selected !== id) return;
  cfgStatus('#cfg-status', '');
  const settings = r.settings && typeof r.settings === 'object' ? r.settings : {};
  cfg.settings = settings;
  cfg.bootTouched = new Set();
  $('#cfg-source').dataset.source = r.source || '';
  setText($('#cfg-source'), r.source ? `(${SOURCE_TEXT[r.source] || r.source})` : '');
  $('#cfg-source').title = r.file ? `kept in ${r.file}` : '';
  $('#cfg-revert').hidden = r.source !== 'state-dir';
  $('#cfg-name').value = settings.name ?? '';
  setText($('#cfg-file'), settings.dcf ?? settings.eds ?? 'none (values arrive raw)');
  const hb = settings['heartbeat-consumer-ms'];
  $('#cfg-hb').value = hb === undefined || hb === null ? '' : String(hb);
  const g = settings.guarding || {};
  $('#cfg-guard').value = g['guard-time-ms'] ?? '';
  $('#cfg-life').value = g['life-time-factor'] ?? '';
  for (const c of document.querySelectorAll('#cfg-form [data-boot]')) c.checked = !!(settings.boot && settings.boot[c.dataset.boot]);
  $('#cfg-metrics').value = (settings['sparkplug-metrics'] || []).join(', ');
}

// The form as the YAML keys of the node's entry. Keys the form does not
// show (the node's file) go back as they came; empty fields are left out
// (the gateway's default). Values go as typed: the gateway checks them.
function settingsFromForm() {
  const s = { ...(cfg.settings || {}) };
  const put = (k, v) => { if (v === undefined || v === '') delete s[k]; else s[k] = v; };
  put('name', $('#cfg-name').value.trim());
  const hb = $('#cfg-hb').value.trim();
  put('heartbeat-consumer-ms', /^\d+$/.test(hb) ? Number(hb) : hb);
  const guard = $('#cfg-guard').value.trim(), life = $('#cfg-life').value.trim();
  if (guard === '' && life === '') delete s.guarding;
  else s.guarding = { 'guard-time-ms': guard === '' ? 0 : Number(guard), 'life-time-factor': life === '' ? 0 : Number(life) };
  // Only the boot keys the node had or the user changed: an absent key
  // keeps its default (read-pdo-config has no plain false one).
  const boot = { ...(s.boot || {}) };
  for (const c of document.querySelectorAll('#cfg-form [data-boot]')) {
    if (c.dataset.boot in boot || cfg.bootTouched.has(c.dataset.boot)) boot[c.dataset.boot] = c.checked;
  }
  if (Object.keys(boot).length) s.boot = boot;
  const metrics = $('#cfg-metrics').value.split(/[\s,]+/).filter(Boolean);
  put('sparkplug-metrics', metrics.length ? metrics : undefined);
  return s;
}

function saveConfig() {
  const id = state.selected;
  const settings = settingsFromForm();
  return cfgRun('Saving', id, '#cfg-status', async () => {
    await roleApi('admin', 'PUT', nodePath(id, 'config'), settings);
    forgetNode(id);
    await loadConfig(id);
    return 'Saved: in use now and kept across restarts.';
  });
}

// DELETE config: state-dir's settings and file go, the configuration file's apply again.
async function revertConfig() {
  const id = state.selected;
  if (!await confirmDialog(`Revert node ${id} to the configuration file?`,
    'The settings changed at run time and an uploaded EDS/DCF are dropped; the configuration file\'s settings ' +
    'for this node apply again at once (a node only configured at run time is no longer configured).', 'Revert')) return;
  return cfgRun('Reverting', id, '#cfg-status', async () => {
    await roleApi('admin', 'DELETE', nodePath(id, 'config'));
    forgetNode(id);
    await loadConfig(id);
    return 'Reverted: the configuration file\'s settings apply.';
  });
}

// The node's file or name changed: its dictionary and row are loaded again.
function forgetNode(id) {
  state.od.delete(id);
  if (state.selected === id) renderOd(id);
  loadNodes().catch(() => {});
}

function uploadEds() {
  const id = state.selected;
  const file = fileOf('#eds-file');
  if (!file) return;
  return cfgRun(`Uploading ${file.name}`, id, '#eds-status', async () => {
    const text = await file.text();
    const r = await roleApi('admin', 'PUT', `${nodePath(id, 'eds')}?name=${encodeURIComponent(file.name)}`, text,
                            { contentType: FILE_TYPE });
    $('#eds-file').value = '';
    forgetNode(id);
    await loadConfig(id);
    const warnings = (r && r.warnings) || [];
    return `${file.name} accepted and in use (object dictionary reloaded).` +
      (warnings.length ? `\nWarnings:\n${warnings.map((w) => (typeof w === 'string' ? w : w.message || JSON.stringify(w))).join('\n')}` : '');
  });
}

// A progress bar and its label; total 0 = indeterminate.
export function setProgress(bar, label, done, total, unit) {
  bar.hidden = false;
  if (total > 0) {
    bar.max = total;
    bar.value = Math.min(done, total);
    const pct = Math.floor((100 * Math.min(done, total)) / total);
    setText(label, `${done.toLocaleString('en')} / ${total.toLocaleString('en')} ${unit || ''} (${pct} %)`);
  } else {
    bar.removeAttribute('value'); // indeterminate until the first progress
    setText(label, '');
  }
}

// ---- store / restore

async function storeNode(restore) {
  const id = state.selected;
  if (restore && !await confirmDialog(`Restore the defaults of node ${id}?`,
    'The device loads its default parameters (1011h sub 1 "load") and is reset: it restarts its application ' +
    'and boots into pre-operational (no process data until started). Stored settings are lost.', 'Restore and reset')) return;
  return cfgRun(restore ? 'Restoring' : 'Storing', id, '#store-status', async () => {
    await roleApi('operator', 'POST', nodePath(id, restore ? 'restore' : 'store'));
    return restore ? 'Defaults restored; the node was reset.' : 'Parameters stored in the device (1010h).';
  });
}

// ---- program download (CiA 302-3)

async function downloadProgram() {
  const id = state.selected;
  const file = fileOf('#prog-file');
  const n = Number($('#prog-n').value);
  if (!file) return;
  if (!Number.isInteger(n) || n < 1 || n > 254) { cfgStatus('#prog-status', 'Program number must be 1..254.', 'error'); return; }
  if (!await confirmDialog(`Download ${file.name} to node ${id}?`,
    `The device stops its program (1F51h), program ${n} is cleared and replaced by ${file.name} ` +
    `(${file.size.toLocaleString('en')} bytes), then started. The device does not do its job meanwhile.`, 'Download')) return;
  setProgress($('#prog-bar'), $('#prog-text'), 0, file.size, 'bytes');
  return cfgRun(`Downloading program ${n}`, id, '#prog-status', async () => {
    const image = await file.arrayBuffer();
    const r = await roleApi('admin', 'PUT', nodePath(id, `program/${n}`), image, { contentType: FILE_TYPE });
    const bytes = Number(r && r.bytes !== undefined ? r.bytes : file.size);
    if (state.selected === id) setProgress($('#prog-bar'), $('#prog-text'), bytes, bytes, 'bytes');
    const ident = r && r.identification;
    return `Program ${n}: ${bytes.toLocaleString('en')} bytes downloaded and started; ` +
      (ident === undefined || ident === null ? 'the device has no program identification (1F56h).'
        : `identification ${fmtValue(ident, 'u32')} (1F56h sub ${n}).`);
  });
}

// `transfer` events of the selected node move the bars, whoever started the
// transfer (this page, another client, MQTT).
export function onTransfer(ev) {
  if (ev.node !== state.selected) return;
  const program = ev.operation === 'program-download';
  const bar = $(program ? '#prog-bar' : '#dcf-bar');
  setProgress(bar, $(program ? '#prog-text' : '#dcf-text'), Number(ev.done) || 0, Number(ev.total) || 0, ev.unit);
  bar.dataset.status = ev.status;
  if (ev.status === 'failed') {
    cfgStatus(program ? '#prog-status' : '#dcf-status',
      `Failed: ${ev.error || 'transfer failed'}${ev.abortCode ? ` (${ev.abortCode})` : ''}${ev.detail ? ` · ${ev.detail}` : ''}`, 'error');
  }
}

export function setupConfig() {
  $('#cfg-form').addEventListener('submit', (e) => { e.preventDefault(); if (state.selected !== null) saveConfig(); });
  $('#cfg-reload').addEventListener('click', () => { if (state.selected !== null) loadConfig(state.selected); });
  $('#cfg-revert').addEventListener('click', revertConfig);
  for (const c of document.querySelectorAll('#cfg-form [data-boot]')) c.addEventListener('change', () => cfg.bootTouched.add(c.dataset.boot));
  $('#eds-file').addEventListener('change', updateConfigButtons);
  $('#prog-file').addEventListener('change', updateConfigButtons);
  $('#eds-upload').addEventListener('click', uploadEds);
  $('#node-store').addEventListener('click', () => storeNode(false));
  $('#node-restore').addEventListener('click', () => storeNode(true));
  $('#prog-start').addEventListener('click', downloadProgram);
}
