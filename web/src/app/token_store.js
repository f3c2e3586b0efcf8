// The bearer token the daemon may require (PROTOCOL.md §6.1), kept in localStorage so that it
// survives reloads and reaches every page of the viewer.
const KEY = 'pointdag.token';

export class TokenStore {
  get() {
    try {
      return localStorage.getItem(KEY) || '';
    } catch {
      return ''; // storage disabled: no token
    }
  }

  set(token) {
    try {
      if (token) localStorage.setItem(KEY, token);
      else localStorage.removeItem(KEY);
    } catch {
      // storage disabled: the token lasts as long as the field's value
    }
  }

  // Headers for a request: the Authorization field when a token is set.
  headers() {
    const token = this.get();
    return token ? { Authorization: `Bearer ${token}` } : {};
  }
}
