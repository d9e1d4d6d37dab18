// Sign in with a token (`lightfarm-server token create`): the server checks it and keeps it in
// an HttpOnly cookie, so the page itself never holds it.
import { post } from './api.js';
import { h } from './format.js';

export function mount(root, _argument, onSignedIn) {
  const input = h('input', { type: 'password', id: 'token', autocomplete: 'off', placeholder: 'lf1_…', required: true });
  const message = h('p', { class: 'error', id: 'signin-error' });
  const form = h('form', {
    id: 'signin',
    onsubmit: async (event) => {
      event.preventDefault();
      message.textContent = '';
      try {
        await post('session', { token: input.value.trim() });
        input.value = '';
        await onSignedIn();
        location.hash = '#/jobs';
      } catch (error) {
        message.textContent = error.message;
      }
    },
  }, h('h1', {}, 'Sign in'), h('label', { for: 'token' }, 'Token'), input,
  h('button', { type: 'submit' }, 'Sign in'), message);
  root.append(form);
  return { refresh: async () => {}, every: 0 };
}
