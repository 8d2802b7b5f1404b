// DCF backup (GET dcf, saved as a file) and restore (POST dcf), with the
// chosen file's values compared with the EDS defaults first.

import { hex } from './util.js';
import { state } from './state.js';
import { $, el, setText, confirmDialog, downloadFile } from './dom.js';
import { keyOf, INT_TYPES, fmtValue } from './format.js';
import { api, roleApi } from './api.js';
import { odOf } from './od.js';
import { cfg, FILE_TYPE, nodePath, cfgStatus, fileOf, updateConfigButtons, cfgRun, cfgErrorText, setProgress } from './config.js';

const objText = (index, sub) => `${hex(index, 4)}h sub ${sub}`;

function failedText(list) {
  return list.map((f) => `${objText(f.index, f.subIndex ?? f.sub ?? 0)}: ${f.error || f.detail || 'failed'}` +
                         `${f.abortCode ? ` (${f.abortCode})` : ''}`).join('; ');
}

function readDcf() {
  const id = state.selected;
  setProgress($('#dcf-bar'), $('#dcf-text'), 0, 0);
  return cfgRun('Reading the DCF', id, '#dcf-status', async () => {
    const r = await api('GET', nodePath(id, 'dcf'), undefined, { accept: 'application/json, text/plain;q=0.5', text: true });
    const doc = r.data && typeof r.data === 'object' ? r.data : null;
    const text = doc ? doc.text ?? doc.dcf ?? '' : r.text;
    const name = `node${id}.dcf`;
    downloadFile(name, text);
    const failed = (doc && (doc.failed || doc.failures)) || [];
    const bar = $('#dcf-bar');
    if (bar.max > 1) bar.value = bar.max;
    return `${name} saved${doc && doc.objects !== undefined ? `: ${doc.objects} objects read` : ''}` +
      (failed.length ? `; not readable: ${failedText(failed)}` : '');
  });
}

// A DCF (CiA 306 INI text) as its values: one row per object/sub-object
// with a ParameterValue. Section names carry the sub-index in hex.
function parseDcf(text) {
  const sections = new Map();
  let cur = null;
  for (const line0 of text.split(/\r?\n/)) {
    const line = line0.trim();
    if (!line || line.startsWith(';')) continue;
    const m = /^\[([^\]]+)\]$/.exec(line);
    if (m) { cur = {}; sections.set(m[1].trim().toLowerCase(), cur); continue; }
    const eq = line.indexOf('=');
    if (cur && eq > 0) cur[line.slice(0, eq).trim().toLowerCase()] = line.slice(eq + 1).trim();
  }
  const rows = [];
  for (const [name, keys] of sections) {
    const m = /^([0-9a-f]{4})(?:sub([0-9a-f]{1,2}))?$/.exec(name);
    if (!m || keys.parametervalue === undefined) continue;
    rows.push({ index: parseInt(m[1], 16), sub: m[2] ? parseInt(m[2], 16) : 0,
                name: keys.parametername || '', value: keys.parametervalue });
  }
  return rows.sort((a, b) => a.index - b.index || a.sub - b.sub);
}

// A CiA 306 integer: decimal, 0x hex, leading-0 octal, with $NODEID terms.
function dcfInteger(text, node) {
  let sum = 0n;
  for (const term of text.replace(/\$NODEID/gi, String(node)).split('+')) {
    const t = term.trim();
    if (/^-?0x[0-9a-f]+$/i.test(t)) sum += t.startsWith('-') ? -BigInt(t.slice(1)) : BigInt(t);
    else if (/^0[0-7]+$/.test(t)) sum += BigInt('0o' + t.slice(1));
    else if (/^-?\d+$/.test(t)) sum += BigInt(t);
    else return null;
  }
  return sum;
}

// Both values in one form, so equal values look equal and compare equal.
function dcfCompare(sub, dcfText, node) {
  const type = sub && sub.type;
  const def = sub ? sub.default : undefined;
  if (type && (INT_TYPES.has(type) || type === 'b')) {
    const v = dcfInteger(dcfText, node);
    let d = null;
    try { d = def === null || def === undefined ? null : BigInt(typeof def === 'boolean' ? Number(def) : def); } catch { d = null; }
    const show = (x) => (x === null ? '–' : type === 'b' ? String(x !== 0n) : fmtValue(x.toString(), type));
    return { dcf: v === null ? dcfText : show(v), eds: show(d), same: v !== null && d !== null && v === d };
  }
  if (type === 'r32' || type === 'r64') {
    const v = Number(dcfText), d = Number(def);
    return { dcf: dcfText, eds: def ?? '–', same: Number.isFinite(v) && v === d };
  }
  const norm = (x) => String(x ?? '').replace(/^0x/i, '').replace(/\s+/g, '').toLowerCase();
  const bytes = type === 'os' || type === 'd';
  return { dcf: dcfText, eds: def ?? '–', same: def !== undefined && def !== null &&
           (bytes ? norm(dcfText) === norm(def) : dcfText === String(def)) };
}

function odEntry(od, index, sub) {
  const o = od && od.objects.find((x) => x.index === index);
  const s = o && o.subs.find((x) => x.subIndex === sub);
  return { obj: o, sub: s, name: o ? (s && s.name && s.name !== o.name ? `${o.name} / ${s.name}` : o.name) : '' };
}

async function chooseDcf() {
  const id = state.selected;
  const file = fileOf('#dcf-file');
  cfg.dcf = null;
  $('#dcf-diff-head').hidden = $('#dcf-diff-wrap').hidden = $('#dcf-results-wrap').hidden = true;
  cfgStatus('#dcf-status', '');
  updateConfigButtons();
  if (!file) return;
  const text = await file.text();
  const rows = parseDcf(text);
  if (!rows.length) {
    cfgStatus('#dcf-status', `${file.name}: no ParameterValue entries: not a DCF of configured values.`, 'error');
    return;
  }
  let od = null;
  try { od = await odOf(id); } catch (e) {
    cfgStatus('#dcf-status', `No EDS defaults to compare with (${cfgErrorText(e)}).`);
  }
  if (state.selected !== id) return;
  const diff = rows.map((r) => {
    const e = odEntry(od, r.index, r.sub);
    const c = dcfCompare(e.sub, r.value, id);
    return { ...r, name: e.name || r.name, eds: e.sub ? c.eds : 'not in the EDS', dcfShown: c.dcf, same: !!e.sub && c.same };
  });
  cfg.dcf = { name: file.name, text, rows: diff };
  renderDcfDiff();
  updateConfigButtons();
}

function renderDcfDiff() {
  const d = cfg.dcf;
  if (!d) return;
  const changed = d.rows.filter((r) => !r.same);
  const all = $('#dcf-diff-all').checked;
  setText($('#dcf-diff-summary'), `${d.name}: ${d.rows.length} values, ${changed.length} differ from the EDS defaults. `);
  $('#dcf-diff-head').hidden = false;
  $('#dcf-diff-wrap').hidden = false;
  const list = all ? d.rows : changed;
  $('#dcf-diff-body').replaceChildren(...(list.length ? list.map((r) => el('tr',
    { 'data-obj': keyOf(r.index, r.sub), 'data-diff': r.same ? '0' : '1' },
    el('td', { text: objText(r.index, r.sub) }),
    el('td', { text: r.name }),
    el('td', { class: 'mono', text: String(r.eds) }),
    el('td', { class: 'mono', text: String(r.dcfShown) })))
    : [el('tr', { class: 'empty' }, el('td', { colspan: 4, text: 'every value equals the EDS default' }))]));
}

async function applyDcf() {
  const id = state.selected;
  const d = cfg.dcf;
  if (!d) return;
  const store = $('#dcf-store').checked, reset = $('#dcf-reset').checked;
  if (reset && !await confirmDialog(`Apply ${d.name} and reset node ${id}?`,
    'The values are written, then the node restarts its application and boots again into pre-operational ' +
    '(no process data until started).', 'Apply and reset')) return;
  setProgress($('#dcf-bar'), $('#dcf-text'), 0, 0);
  $('#dcf-results-wrap').hidden = true;
  return cfgRun(`Applying ${d.name}`, id, '#dcf-status', async () => {
    const q = [store ? 'store=true' : null, reset ? 'reset=true' : null].filter(Boolean).join('&');
    const r = await roleApi('admin', 'POST', `${nodePath(id, 'dcf')}${q ? '?' + q : ''}`, d.text,
                            { contentType: FILE_TYPE });
    const objects = (r && (r.objects || r.results)) || [];
    let od = null;
    try { od = await odOf(id); } catch { od = null; }
    const failed = objects.filter((o) => objectFailed(o));
    if (state.selected === id) {
      $('#dcf-results-body').replaceChildren(...objects.map((o) => {
        const sub = o.subIndex ?? o.sub ?? 0;
        const bad = objectFailed(o);
        return el('tr', { 'data-obj': keyOf(o.index, sub), 'data-result': bad ? 'failed' : 'ok' },
          el('td', { text: objText(o.index, sub) }),
          el('td', { text: odEntry(od, o.index, sub).name }),
          el('td', { text: bad ? `${o.error || o.detail || 'failed'}${o.abortCode ? ` (${o.abortCode})` : ''}` : 'written' }));
      }));
      $('#dcf-results-wrap').hidden = false;
      const bar = $('#dcf-bar');
      if (bar.max > 1) bar.value = bar.max;
    }
    const storeError = r && r.storeError ? `; store failed: ${r.storeError.error || 'failed'}` +
      `${r.storeError.abortCode ? ` (${r.storeError.abortCode})` : ''}` : '';
    const extra = [r && r.stored ? 'stored' : null, r && r.reset ? 'node reset' : null].filter(Boolean).join(', ');
    const text = `${objects.length - failed.length} of ${objects.length} objects written${extra ? ', ' + extra : ''}`;
    if (failed.length || storeError) throw new Error(`${text}${failed.length ? `; ${failed.length} failed (highlighted below)` : ''}${storeError}`);
    return text + '.';
  });
}

const objectFailed = (o) => !!(o.error || o.abortCode) || o.ok === false || o.status === 'failed';

export function setupDcf() {
  $('#dcf-read').addEventListener('click', readDcf);
  $('#dcf-file').addEventListener('change', chooseDcf);
  $('#dcf-diff-all').addEventListener('change', renderDcfDiff);
  $('#dcf-apply').addEventListener('click', applyDcf);
}
