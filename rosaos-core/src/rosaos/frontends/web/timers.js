// Timers ("turn off the light in ten minutes"): pending ones with a countdown and a Cancel button.
// Shown only when the kernel has the timers API (its OpenAPI lists /timers, see TIMERS_API);
// refreshed when the updates stream says timers changed, and every 30 s to be safe.

import { $, api, errorText, page, setStatus, SignedOut } from "./session.js";

const REFRESH_MS = 30_000;
const TIMER_TOOLS = new Set(["set_timer", "list_timers", "cancel_timer"]);
const state = { enabled: false, offset: 0, timers: [] };

/** Ask the kernel's OpenAPI (public) whether it has timers; show the panel and start if so. */
export async function detectTimers() {
  try {
    const response = await fetch("/openapi.json", { cache: "no-store" });
    state.enabled = response.ok && Boolean((await response.json()).paths?.["/timers"]);
  } catch (_) {
    state.enabled = false;
  }
  $("#timers-panel").hidden = !state.enabled;
  if (!state.enabled) return;
  refreshTimers();
  setInterval(() => { if (page.running) refreshTimers(); }, REFRESH_MS);
  setInterval(tick, 1000);
}

export async function refreshTimers() {
  if (!state.enabled) return;
  try {
    const response = await api("/timers");
    if (!response.ok) return;
    const body = await response.json();
    // Count down on the kernel's clock, not this device's.
    state.offset = Date.parse(body.now) - Date.now();
    state.timers = body.timers || [];
    render();
  } catch (error) {
    if (!(error instanceof SignedOut)) setStatus($("#timers-status"), "Timers: the kernel cannot be reached.", "error");
  }
}

/** An update from the stream: refetch when it is about timers. */
export function timersUpdate(update) {
  const data = update.data || {};
  const aboutTimers = (update.kind === "tool_call" && TIMER_TOOLS.has(data.tool))
    || (update.kind === "event" && data.kind === "timer_fired")
    || (update.kind === "notice" && data.timer);
  if (aboutTimers) refreshTimers();
}

function inWords(ms) {
  const seconds = Math.max(0, Math.round(ms / 1000));
  if (seconds < 60) return `in ${seconds} s`;
  const minutes = Math.round(seconds / 60);
  if (minutes < 90) return `in ${minutes} min`;
  return `in ${Math.floor(minutes / 60)} h ${minutes % 60} min`;
}

function render() {
  const list = $("#timers");
  $("#timers-empty").hidden = state.timers.length > 0;
  list.replaceChildren(...state.timers.map((timer) => {
    const item = document.createElement("li");
    item.dataset.timer = timer.id;
    const action = document.createElement("span");
    action.className = "timer-action";
    action.textContent = timer.action;
    const due = document.createElement("time");
    due.dateTime = timer.due;
    due.dataset.due = timer.due;
    const cancel = document.createElement("button");
    cancel.type = "button";
    cancel.className = "danger";
    cancel.textContent = "Cancel";
    cancel.dataset.cancelTimer = timer.id;
    cancel.setAttribute("aria-label", `Cancel timer ${timer.id}: ${timer.action}`);
    item.append(action, due, cancel);
    return item;
  }));
  tick();
}

function tick() {
  const now = Date.now() + state.offset;
  for (const due of document.querySelectorAll("#timers time[data-due]")) {
    const at = Date.parse(due.dataset.due);
    due.textContent = `${new Date(at).toLocaleTimeString()} (${inWords(at - now)})`;
  }
}

/** Clicks on Cancel. Wired once on the list. */
export async function cancelTimer(event) {
  const button = event.target.closest("button[data-cancel-timer]");
  if (!button) return;
  const status = $("#timers-status");
  button.disabled = true;
  try {
    const response = await api(`/timers/${button.dataset.cancelTimer}`, { method: "DELETE" });
    if (response.ok) setStatus(status, `Timer ${button.dataset.cancelTimer} cancelled.`);
    else setStatus(status, `Could not cancel: ${await errorText(response)}`, "error");
  } catch (error) {
    if (!(error instanceof SignedOut)) setStatus(status, "Could not cancel: the kernel cannot be reached.", "error");
  } finally {
    refreshTimers();
  }
}
