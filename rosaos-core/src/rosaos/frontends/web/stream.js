// The updates stream: server-sent events over fetch, or polling, into the chat and event logs.

import { $, api, errorText, page, setConnection, SignedOut, sleep, timeOf } from "./session.js";
import { timelineUpdate } from "./timeline.js";
import { timersUpdate } from "./timers.js";
import { setMarkedText, titled } from "./words.js";
import { showSightingPicture } from "./sighting_pictures.js";

const POLL_MS = 1000;
const MAX_LINES = 300; // keep the DOM small: older chat and event lines are dropped
const STREAM_FAILURES_BEFORE_POLLING = 3;
const REPEAT_WINDOW_MS = 120_000; // the same line again within this long is counted, not repeated
const processesOf = new Map(); // event id -> ids of the processes it launched or that it reported

export async function followUpdates() {
  const canStream = typeof TextDecoderStream === "function" && "body" in Response.prototype;
  let failures = canStream ? 0 : STREAM_FAILURES_BEFORE_POLLING;
  while (page.running) {
    try {
      if (failures < STREAM_FAILURES_BEFORE_POLLING) {
        const delivered = await streamUpdates();
        failures = delivered ? 0 : failures + 1;
      } else {
        await pollUpdates();
        await sleep(POLL_MS);
        continue;
      }
    } catch (error) {
      if (error instanceof SignedOut) return;
      failures += 1;
      setConnection("offline", "Reconnecting…");
    }
    await sleep(Math.min(1000 * failures, 5000));
  }
}

// Server-sent events over fetch, so the token travels in the Authorization header rather than
// in the URL (EventSource cannot set headers). Returns whether any bytes arrived: the server
// sends a comment at once, so a stream that stays silent sits behind a buffering proxy.
async function streamUpdates() {
  page.streamAbort = new AbortController();
  const headers = { Accept: "text/event-stream" };
  if (page.lastUpdateId) headers["Last-Event-ID"] = String(page.lastUpdateId);
  const response = await api("/updates", { headers, signal: page.streamAbort.signal });
  if (!response.ok || !response.body) throw new Error(await errorText(response));
  setConnection("live", "Live");
  const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
  let buffer = "";
  let data = [];
  let delivered = false;
  for (;;) {
    const { value, done } = await reader.read();
    if (done) break;
    delivered = true;
    buffer += value;
    let end;
    while ((end = buffer.search(/\r\n|\r|\n/)) !== -1) {
      if (buffer[end] === "\r" && end === buffer.length - 1) break; // maybe half of a \r\n
      const width = buffer.startsWith("\r\n", end) ? 2 : 1;
      const line = buffer.slice(0, end);
      buffer = buffer.slice(end + width);
      if (line === "") {
        if (data.length) addUpdate(JSON.parse(data.join("\n")));
        data = [];
      } else if (line.startsWith("data:")) {
        data.push(line.slice(5).replace(/^ /, ""));
      }
      // id:, retry: and comments need no handling: the update carries its own id.
    }
  }
  setConnection("offline", "Reconnecting…");
  return delivered;
}

async function pollUpdates() {
  const query = page.lastUpdateId ? `?after=${page.lastUpdateId}&limit=200` : "?limit=200";
  const response = await api(`/updates${query}`);
  if (!response.ok) throw new Error(await errorText(response));
  const body = await response.json();
  body.updates.forEach(addUpdate);
  setConnection("polling", "Live (polling)");
}

function addUpdate(update) {
  // The server only sends ids above the one we asked after. A lower id means its store was
  // reset (a new data directory), so follow the new numbering instead of ignoring it.
  page.lastUpdateId = update.id;
  appendEventLine(update);
  timelineUpdate(update);
  timersUpdate(update);
  noteProcesses(update);
  const chat = chatLine(update);
  if (chat) appendChatLine(update, chat);
}

// Which processes an event concerns, so the kernel's reply to it can point at them in Activity.
function noteProcesses(update) {
  const data = update.data || {};
  const id = update.kind === "process_launched" ? data.process_id
    : update.kind === "event" && data.kind === "worker_callback" ? data.payload?.process_id : null;
  if (id == null || update.event_id == null) return;
  const known = processesOf.get(update.event_id) || [];
  if (!known.includes(id)) known.push(id);
  processesOf.set(update.event_id, known);
}

function appendEventLine(update) {
  const log = $("#events");
  const item = document.createElement("li");
  item.dataset.updateId = update.id;
  item.dataset.kind = update.kind;
  const time = document.createElement("time");
  time.dateTime = update.time;
  time.textContent = timeOf(update.time);
  const kind = document.createElement("span");
  kind.className = "kind";
  kind.textContent = update.kind;
  const text = document.createElement("span");
  text.className = "text";
  text.textContent = update.text;
  item.append(time, kind, text);
  appendKeepingScroll(log, item);
}

// How an update reads in the chat, or null when it belongs only in Activity or the Debug view.
// The chat is the conversation: what you said, and one line per outcome from rosaOS. Processes
// starting and ending, tool calls and worker callbacks are in Activity; everything in Debug.
function chatLine(update) {
  const data = update.data || {};
  if (update.kind === "kernel_reply") return { who: "rosaOS", role: "kernel", text: update.text };
  if (update.kind === "error") return { who: "Error", role: "error", text: update.text };
  if (update.kind !== "event") return null;
  const payload = data.payload || {};
  switch (data.kind) {
    case "user_typed": return { who: "You", role: "user", text: payload.text };
    case "user_said": return { who: "You said", role: "user", text: payload.text };
    case "device_notice": return { who: titled(payload.device), role: "system", text: payload.message };
    case "error": return { who: "Error", role: "error", text: payload.message };
    default: return null;
  }
}

function appendChatLine(update, line) {
  const log = $("#chat-log");
  const last = [...log.children].slice(-4).reverse().find((item) => item.dataset.text === line.text);
  if (last && line.role !== "user" && Date.now() - Number(last.dataset.at) < REPEAT_WINDOW_MS) {
    if (last.dataset.who !== line.who) return; // rosaOS repeating a device's notice: said already
    const count = Number(last.dataset.count || "1") + 1; // "found a person" three times is one line, ×3
    last.dataset.count = String(count);
    $(".repeat", last).textContent = `×${count}`;
    $(".repeat", last).hidden = false;
    return;
  }
  const item = document.createElement("li");
  item.className = `msg msg-${line.role}`;
  item.dataset.updateId = update.id;
  item.dataset.role = line.role;
  item.dataset.text = line.text || "";
  item.dataset.who = line.who;
  item.dataset.at = String(Date.now());
  if (line.who) {
    const who = document.createElement("span");
    who.className = "who";
    who.textContent = `${line.who}:`;
    item.append(who);
  }
  const text = document.createElement("span");
  text.className = "msg-text";
  setMarkedText(text, line.text || "");
  const repeat = document.createElement("span");
  repeat.className = "repeat";
  repeat.hidden = true;
  item.append(text, repeat);
  const processes = line.role === "kernel" ? processesOf.get(update.event_id) || [] : [];
  if (processes.length) {
    // Details on click: the processes behind this answer, in Activity.
    const more = document.createElement("button");
    more.type = "button";
    more.className = "msg-more quiet";
    more.textContent = "Details";
    more.dataset.processes = processes.join(",");
    more.setAttribute("aria-label", `Show process ${processes.join(", ")} in Activity`);
    item.append(more);
  }
  appendKeepingScroll(log, item);
  if (line.role === "kernel") showSightingPicture(item, line.text); // "show me": the picture it names
}

/** A chat line's Details: bring its processes into view in Activity and mark them. */
export function showChatDetails(event) {
  const button = event.target.closest("button.msg-more");
  if (!button) return;
  const entries = button.dataset.processes.split(",")
    .map((id) => document.querySelector(`#timeline > li[data-process="${id}"]`)).filter(Boolean);
  for (const entry of document.querySelectorAll("#timeline > li.highlight")) entry.classList.remove("highlight");
  for (const entry of entries) entry.classList.add("highlight");
  entries[0]?.scrollIntoView({ block: "nearest", behavior: "smooth" });
  entries[0]?.setAttribute("tabindex", "-1");
  entries[0]?.focus({ preventScroll: true });
}

function appendKeepingScroll(list, item) {
  const atBottom = list.scrollHeight - list.scrollTop - list.clientHeight < 40;
  list.append(item);
  while (list.children.length > MAX_LINES) list.firstElementChild.remove();
  if (atBottom) list.scrollTop = list.scrollHeight;
}
