// The updates stream: server-sent events over fetch, or polling, into the chat and event logs.

import { $, api, errorText, page, setConnection, SignedOut, sleep, timeOf } from "./session.js";
import { timelineUpdate } from "./timeline.js";
import { timersUpdate } from "./timers.js";

const POLL_MS = 1000;
const MAX_LINES = 300; // keep the DOM small: older chat and event lines are dropped
const STREAM_FAILURES_BEFORE_POLLING = 3;

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
  const chat = chatLine(update);
  if (chat) appendChatLine(update.id, chat);
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

// How an update reads in the chat, or null when it belongs only in the event stream.
function chatLine(update) {
  const data = update.data || {};
  if (update.kind === "kernel_reply") return { who: "rosaOS", role: "kernel", text: update.text };
  if (update.kind === "error") return { who: "Error", role: "error", text: update.text };
  if (update.kind === "process_launched" || update.kind === "process_ended") {
    return { who: "", role: "system", text: update.text };
  }
  if (update.kind !== "event") return null;
  const payload = data.payload || {};
  switch (data.kind) {
    case "user_typed": return { who: "You", role: "user", text: payload.text };
    case "user_said": return { who: "You said", role: "user", text: payload.text };
    case "worker_callback": {
      const result = payload.error || payload.output || "";
      return { who: `Process ${payload.process_id ?? payload.worker_id} (${payload.status})`, role: "system", text: result };
    }
    case "device_notice": return { who: payload.device, role: "system", text: payload.message };
    case "error": return { who: "Error", role: "error", text: payload.message };
    default: return { who: "", role: "system", text: update.text };
  }
}

function appendChatLine(id, line) {
  const item = document.createElement("li");
  item.className = `msg msg-${line.role}`;
  item.dataset.updateId = id;
  item.dataset.role = line.role;
  if (line.who) {
    const who = document.createElement("span");
    who.className = "who";
    who.textContent = `${line.who}:`;
    item.append(who);
  }
  item.append(document.createTextNode(line.text || ""));
  appendKeepingScroll($("#chat-log"), item);
}

function appendKeepingScroll(list, item) {
  const atBottom = list.scrollHeight - list.scrollTop - list.clientHeight < 40;
  list.append(item);
  while (list.children.length > MAX_LINES) list.firstElementChild.remove();
  if (atBottom) list.scrollTop = list.scrollHeight;
}
