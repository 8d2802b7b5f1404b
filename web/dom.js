// DOM helpers. Elements are built with textContent only: names and
// descriptions come from EDS files and devices and must never be
// interpreted as HTML.

export const $ = (sel, root = document) => root.querySelector(sel);

export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k === 'class') e.className = v;
    else if (k === 'text') e.textContent = v;
    else if (k.startsWith('data-') || k === 'title' || k === 'type' || k === 'role' || k.startsWith('aria-') ||
             k === 'colspan' || k === 'placeholder' || k === 'name' || k === 'value' || k === 'spellcheck' ||
             k === 'tabindex')
      e.setAttribute(k, v === true ? '' : String(v));
    else e[k] = v;
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
}

export function setText(node, text) {
  const s = String(text);
  if (node && node.textContent !== s) node.textContent = s;
}

export function toast(message, kind = 'info') {
  const t = el('div', { class: 'toast', 'data-kind': kind, role: kind === 'error' ? 'alert' : 'status', text: message });
  t.addEventListener('click', () => t.remove());
  $('#toasts').append(t);
  while ($('#toasts').children.length > 5) $('#toasts').firstElementChild.remove();
  setTimeout(() => t.remove(), kind === 'error' ? 10_000 : 3_500);
}

// A modal question; resolves true when the user confirmed.
export function confirmDialog(title, message, okText) {
  const d = $('#confirm');
  setText($('#confirm-title'), title);
  setText($('#confirm-message'), message);
  setText($('#confirm-ok'), okText);
  d.returnValue = '';
  d.showModal();
  $('#confirm-cancel').focus(); // Enter on an unexpected dialog must not stop a machine
  return new Promise((resolve) => d.addEventListener('close', () => resolve(d.returnValue === 'ok'), { once: true }));
}

export function downloadFile(name, text, type = 'text/plain') {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = el('a', { href: url, download: name, hidden: true });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
}
