// "Running now", pinned at the top of the page: each running process with its sentence, the
// devices it holds, its progress bar and last message, what the kernel does after it ("then: turn
// the lamp green") and a Stop button. A long search stays in sight however long Activity grows.

import { $, api, errorText, setStatus, SignedOut, timeOf } from "./session.js";
import { progressOf } from "./timeline.js";
import { spaced } from "./words.js";

function element(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined) node.textContent = text;
  return node;
}

function setText(node, text) {
  if (node.textContent !== text) node.textContent = text;
}

function build(process) {
  const item = element("li", "run");
  item.dataset.process = process.id;
  const head = element("div", "run-head");
  const stop = element("button", "danger", "Stop");
  stop.type = "button";
  stop.dataset.terminate = process.id;
  stop.setAttribute("aria-label", `Stop process ${process.id}`);
  head.append(element("p", "run-task"), stop);
  const progress = element("div", "run-progress");
  progress.append(element("progress"), element("span", "run-progress-text"));
  item.append(head, element("p", "run-meta"), progress, element("p", "run-then"));
  return item;
}

/** The running-processes poll (GET /processes). */
export function renderRunning(processes) {
  const running = processes.filter((p) => p.state === "running").sort((a, b) => a.id - b.id);
  const panel = $("#running-panel");
  const list = $("#running");
  panel.hidden = running.length === 0;
  const wanted = new Set(running.map((p) => String(p.id)));
  for (const item of [...list.children]) if (!wanted.has(item.dataset.process)) item.remove();
  for (const process of running) {
    let item = $(`:scope > li[data-process="${process.id}"]`, list);
    if (!item) {
      item = build(process);
      list.append(item);
    }
    setText($(".run-task", item), process.summary || "(no task)");
    const devices = (process.devices || []).map(spaced).join(", ") || "no device";
    const since = process.started_at ? `, since ${timeOf(process.started_at)}` : "";
    setText($(".run-meta", item), `Process ${process.id} with ${devices}${since}`);
    const then = $(".run-then", item);
    then.hidden = !process.then;
    setText(then, process.then ? `Then: ${process.then}` : "");
    showProgress($(".run-progress", item), process);
  }
}

function showProgress(box, process) {
  const progress = progressOf(process.progress);
  const bar = $("progress", box);
  bar.setAttribute("aria-label", `Progress of process ${process.id}`);
  if (!progress || (progress.fraction == null && !progress.message)) {
    bar.removeAttribute("value"); // indeterminate: it runs, but has said nothing yet
    setText($(".run-progress-text", box), "Working…");
    return;
  }
  const { fraction, message } = progress;
  if (typeof fraction === "number") bar.value = Math.max(0, Math.min(1, fraction));
  else bar.removeAttribute("value");
  const percent = typeof fraction === "number" ? `${Math.round(Math.max(0, Math.min(1, fraction)) * 100)} %` : "";
  setText($(".run-progress-text", box), [percent, message].filter(Boolean).join(" · "));
}

/** A Stop button: terminate the process (its leases are released, its device put at rest). */
export async function stopProcess(event) {
  const button = event.target.closest("button[data-terminate]");
  if (!button) return;
  const id = button.dataset.terminate;
  const status = $("#running-status");
  button.disabled = true;
  try {
    const response = await api(`/processes/${id}/terminate`, { method: "POST" });
    if (!response.ok) setStatus(status, `Could not stop process ${id}: ${await errorText(response)}`, "error");
    else setStatus(status, `Process ${id} stopped.`);
  } catch (error) {
    if (!(error instanceof SignedOut)) setStatus(status, `Could not stop process ${id}: the kernel cannot be reached.`, "error");
  } finally {
    button.disabled = false;
  }
}
