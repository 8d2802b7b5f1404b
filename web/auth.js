// The access token: the prompt when the gateway answers 401, and the
// header's Token button.

import { state, setToken } from './state.js';
import { $, el } from './dom.js';
import { setWs } from './header.js';
import { closeWs } from './events.js';

export function needToken(detail) {
  state.authBlocked = true;
  closeWs();
  setWs('closed', 'token needed');
  if (!state.nodes.size) {
    $('#nodes-body').replaceChildren(el('tr', { class: 'empty' }, el('td', { colspan: 6, text: 'token required' })));
  }
  const msg = state.token
    ? `The gateway refused the stored token (${detail}). Enter a valid token.`
    : 'This gateway requires an access token. Enter it to continue.';
  openTokenDialog(msg, true);
}

function openTokenDialog(message, isError) {
  const box = $('#auth-prompt');
  $('#auth-message').textContent = message;
  $('#auth-message').classList.toggle('err', !!isError);
  box.dataset.reason = isError ? 'required' : 'manual';
  box.hidden = false;
  $('#token-input').value = '';
  $('#token-input').focus();
}

function closeTokenDialog() { $('#auth-prompt').hidden = true; }

// restart: called once the token changed (the network is loaded again with it).
export function setupToken(restart) {
  $('#token-button').addEventListener('click', () =>
    openTokenDialog(state.token ? 'A token is stored in this browser. Enter another one to replace it.'
                                : 'No token is stored. The gateway may not need one.', false));
  $('#token-cancel').addEventListener('click', closeTokenDialog);
  $('#token-clear').addEventListener('click', () => {
    setToken('');
    closeTokenDialog();
    updateTokenButton();
    restart();
  });
  $('#token-form').addEventListener('submit', (e) => {
    e.preventDefault();
    const t = $('#token-input').value.trim();
    if (!t) { $('#auth-message').textContent = 'Enter a token.'; return; }
    setToken(t);
    closeTokenDialog();
    updateTokenButton();
    restart();
  });
  document.addEventListener('keydown', (e) => {
    if (e.key === 'Escape' && !$('#auth-prompt').hidden) closeTokenDialog();
  });
  updateTokenButton();
}

function updateTokenButton() {
  const b = $('#token-button');
  b.textContent = state.token ? 'Token ✓' : 'Token';
  b.dataset.hasToken = state.token ? '1' : '0';
}
