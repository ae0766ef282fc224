// The session with the kernel: the token, authenticated fetch, login and sign-out.

const TOKEN_KEY = "rosaos.token";

export const $ = (selector, root = document) => root.querySelector(selector);
export const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

export const page = {
  token: sessionStorage.getItem(TOKEN_KEY),
  lastUpdateId: 0,
  running: false,
  streamAbort: null,
};

/** Thrown by api() after a 401: the page has signed out and shows the login message. */
export class SignedOut extends Error {}

export async function api(path, options = {}) {
  const headers = { ...(options.headers || {}), Authorization: `Bearer ${page.token}` };
  if (options.json !== undefined) headers["Content-Type"] = "application/json";
  const response = await fetch(path, {
    method: options.method || "GET",
    headers,
    body: options.json !== undefined ? JSON.stringify(options.json) : undefined,
    cache: "no-store",
    signal: options.signal,
  });
  if (response.status === 401) {
    signOut("Your session has ended (the kernel restarted or the token changed). Open a new login link.");
    throw new SignedOut();
  }
  return response;
}

export async function errorText(response) {
  try {
    const body = await response.json();
    if (typeof body.detail === "string") return body.detail;
  } catch (_) { /* not JSON: fall through */ }
  return `HTTP ${response.status}`;
}

export function newKey() {
  // crypto.randomUUID needs a secure context; a LAN address over http is not one.
  if (crypto.randomUUID) return crypto.randomUUID();
  const bytes = crypto.getRandomValues(new Uint8Array(16));
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}

// --- login -------------------------------------------------------------------------------------

export function takeLoginCode() {
  const match = /(?:^#|&)login=([^&]+)/.exec(location.hash);
  if (!match) return null;
  // Drop the code from the address bar and history: it is single-use anyway, but a copied URL
  // should not carry it around.
  history.replaceState(null, "", location.pathname + location.search);
  return decodeURIComponent(match[1]);
}

export async function login(code) {
  const response = await fetch("/login", {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify({ code }),
    cache: "no-store",
  });
  if (!response.ok) {
    // The section above already says how to get a fresh link: say only what went wrong.
    $("#login-error").textContent = response.status === 401
      ? "This login link was already used, has expired, or is unknown."
      : `Could not sign in: ${await errorText(response)}`;
    return;
  }
  const body = await response.json();
  page.token = body.token;
  sessionStorage.setItem(TOKEN_KEY, page.token);
}

export function signOut(message) {
  page.token = null;
  page.running = false;
  if (page.streamAbort) page.streamAbort.abort();
  sessionStorage.removeItem(TOKEN_KEY);
  $("#app").hidden = true;
  $("#sign-out").hidden = true;
  $("#login-needed").hidden = false;
  $("#login-error").textContent = message || "";
  setConnection("offline", "Not connected");
}

export function setConnection(state, text) {
  const element = $("#connection");
  element.dataset.state = state;
  element.textContent = text;
}

export function timeOf(iso) {
  const date = new Date(iso);
  return Number.isNaN(date.getTime()) ? "" : date.toLocaleTimeString();
}

export function setStatus(element, text, kind = "info") {
  element.textContent = text;
  element.dataset.kind = kind;
}

export function setBadge(parent, status) {
  let badge = $(".badge", parent);
  if (!badge) {
    badge = document.createElement("span");
    badge.className = "badge";
    parent.append(badge);
  }
  badge.dataset.status = status;
  badge.textContent = status;
}
