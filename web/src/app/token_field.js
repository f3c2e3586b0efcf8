// The token field: always shown (a daemon may require a token for writes, or for reads too);
// what is typed is kept by TokenStore. attention() highlights it after a 401.
import { h } from './dom.js';

export class TokenField {
  constructor(tokens, onChange) {
    this.input = h('input#token', { type: 'password', autocomplete: 'off', placeholder: 'none', value: tokens.get() });
    this.hint = h('span.muted#token-hint', {}, 'sent as Authorization: Bearer, kept in this browser');
    this.input.addEventListener('change', () => {
      tokens.set(this.input.value.trim());
      this.element.classList.remove('attention');
      onChange();
    });
    // A form of its own, so that password managers and Enter behave.
    this.element = h('form.card.token', { on: { submit: (e) => e.preventDefault() } },
      h('label', {}, 'Token', this.input), this.hint);
  }

  attention() {
    this.element.classList.add('attention');
    this.hint.textContent = 'the daemon requires a token: enter it here';
    this.input.focus();
  }
}
