// Token entry: asks for the API token, keeps it in sessionStorage only (gone when the tab closes).
import { byTestId } from './dom';

const KEY = 'corridor.token';

export function storedToken(): string | null {
  return sessionStorage.getItem(KEY);
}

export function forgetToken(): void {
  sessionStorage.removeItem(KEY);
}

export function showLogin(error: string, onToken: (token: string) => void): void {
  const login = byTestId('login');
  const form = byTestId<HTMLFormElement>('login-form');
  const input = byTestId<HTMLInputElement>('token-input');
  byTestId('app').hidden = true;
  login.hidden = false;
  byTestId('login-error').textContent = error;
  input.value = '';
  input.focus();
  form.onsubmit = (e) => {
    e.preventDefault();
    const token = input.value.trim();
    if (!token) return;
    sessionStorage.setItem(KEY, token);
    onToken(token);
  };
}

export function hideLogin(): void {
  byTestId('login').hidden = true;
  byTestId('app').hidden = false;
}
