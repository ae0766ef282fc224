// The activity timeline: one entry per process, newest first. It shows the launch, every tool call
// with its result (the receipts the worker's callback carries, as in `rosaos log`), the callback,
// the progress a running process reports, and Yes/No buttons for a question waiting on a person.

import { $, api, errorText, setBadge, setStatus, SignedOut, timeOf } from "./session.js";
import { callLine, resultLine, spaced } from "./words.js";

const MAX_PROCESSES = 30;
const RESULT_CHARS = 160;

export const taskTitle = (task) => (task || "").split("\n\n")[0].trim() || "(no task)";

function element(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined) node.textContent = text;
  return node;
}

function entryFor(id, task) {
  const list = $("#timeline");
  let entry = list.querySelector(`:scope > li[data-process="${id}"]`);
  if (!entry) {
    entry = element("li", "tl-process");
    entry.dataset.process = id;
    const header = element("div", "tl-header");
    header.append(element("h3", "tl-title", `Process ${id}`), element("span", "badge-slot"));
    const progress = element("div", "tl-progress");
    progress.hidden = true;
    progress.append(element("progress"), element("span", "tl-progress-text"));
    entry.append(header, element("p", "tl-task"), progress, element("div", "tl-questions"), element("ol", "tl-steps"));
    entry.setAttribute("aria-label", `Process ${id}`);
    // Newest first: a higher id goes above the lower ones.
    const after = [...list.children].find((child) => Number(child.dataset.process) < id);
    list.insertBefore(entry, after || null);
    while (list.children.length > MAX_PROCESSES) list.lastElementChild.remove();
    $("#timeline-empty").hidden = true;
  }
  if (task) $(".tl-task", entry).textContent = taskTitle(task);
  return entry;
}

function step(entry, kind, time, text, detail) {
  const item = element("li", `tl-step tl-${kind}`);
  item.dataset.step = kind;
  const when = element("time", "", time ? timeOf(time) : "");
  if (time) when.dateTime = time;
  item.append(when, element("span", "tl-text", text));
  if (detail) item.append(element("span", "tl-detail", detail));
  $(".tl-steps", entry).append(item);
  return item;
}

// A process's own words, without markdown marks, on one short line.
function short(text) {
  if (!text) return "";
  const line = String(text).replace(/`|\*\*|__/g, "").replace(/\s+/g, " ").trim();
  return line.length > RESULT_CHARS ? `${line.slice(0, RESULT_CHARS)}…` : line;
}

const ENDINGS = { ok: "Done", terminated: "Stopped", timeout: "Gave up (took too long)", error: "Failed" };

/** Feed one update of the stream; only process launches and ends concern the timeline. */
export function timelineUpdate(update) {
  const data = update.data || {};
  if (update.kind === "process_launched" && data.process_id) {
    const entry = entryFor(data.process_id);
    if (!$(".tl-launched", entry)) {
      step(entry, "launched", update.time, `Started with ${(data.devices || []).map(spaced).join(", ") || "no device"}`);
    }
    setBadge($(".badge-slot", entry), data.state || "running");
  } else if (update.kind === "process_ended" && (data.process_id ?? data.worker_id)) {
    // Updates stored before the rename carry worker_id.
    const entry = entryFor(data.process_id ?? data.worker_id, data.task);
    if ($(".tl-callback", entry)) return; // a replayed update
    for (const receipt of data.receipts || []) {
      const at = receipt.started ? new Date(receipt.started * 1000).toISOString() : update.time;
      const detail = receipt.ok ? resultLine(receipt.result) : short(receipt.error);
      const item = step(entry, receipt.ok ? "call" : "call-failed", at, `${receipt.ok ? "✓" : "✗"} ${callLine(receipt)}`, detail);
      item.dataset.tool = receipt.tool;
      if (receipt.safety) item.append(element("span", "tl-safety", `Safety: ${spaced(receipt.safety.decision)}${receipt.safety.detail ? `, ${short(receipt.safety.detail)}` : ""}`));
    }
    const result = data.error || data.output || "";
    const item = step(entry, "callback", update.time, ENDINGS[data.status] || spaced(data.status), short(result));
    item.dataset.status = data.status;
    setBadge($(".badge-slot", entry), data.status);
    $(".tl-progress", entry).hidden = true;
  }
}

/** The processes poll: task titles, states and the progress of running ones. */
export function timelineProcesses(processes) {
  const newest = [...processes].sort((a, b) => b.id - a.id).slice(0, MAX_PROCESSES);
  for (const process of newest) {
    const entry = entryFor(process.id, process.task);
    if (process.state === "running" && !$(".tl-question", entry)) setBadge($(".badge-slot", entry), "running");
    showProgress(entry, process);
  }
}

// Progress a running process reports (PROGRESS_API): {"progress": 7.2, "total": 120, "message": "…"}
// (a share when total is set, else an indeterminate bar with the message), or a bare 0-1 number.
export function progressOf(raw) {
  if (typeof raw === "number") return { fraction: raw, message: "" };
  if (!raw || typeof raw !== "object") return null;
  const fraction = typeof raw.progress === "number" && typeof raw.total === "number" && raw.total > 0
    ? raw.progress / raw.total : null;
  return { fraction, message: resultLine(raw.message || "") };
}

function showProgress(entry, process) {
  const box = $(".tl-progress", entry);
  const progress = progressOf(process.progress);
  if (process.state !== "running" || !progress || (progress.fraction == null && !progress.message)) {
    box.hidden = true;
    return;
  }
  box.hidden = false;
  const bar = $("progress", box);
  const { fraction, message } = progress;
  if (typeof fraction === "number") bar.value = Math.max(0, Math.min(1, fraction));
  else bar.removeAttribute("value"); // indeterminate
  bar.setAttribute("aria-label", `Progress of process ${process.id}`);
  const percent = typeof fraction === "number" ? `${Math.round(Math.max(0, Math.min(1, fraction)) * 100)} %` : "";
  $(".tl-progress-text", box).textContent = [percent, message].filter(Boolean).join(" · ");
}

/** The confirmations poll: each pending question gets Yes/No buttons in its process's entry. */
export function renderConfirmations(body) {
  const pending = body.confirmations || [];
  const wanted = new Set(pending.map((c) => String(c.id)));
  for (const old of document.querySelectorAll("#timeline .tl-question")) if (!wanted.has(old.dataset.confirmation)) old.remove();
  for (const question of pending) {
    const entry = entryFor(question.process_id);
    if ($(`.tl-question[data-confirmation="${question.id}"]`, entry)) continue;
    const box = element("div", "tl-question");
    box.dataset.confirmation = question.id;
    box.setAttribute("role", "group");
    const textId = `confirmation-${question.id}`;
    const text = element("p", "tl-question-text", question.question);
    text.id = textId;
    box.setAttribute("aria-labelledby", textId);
    const yes = element("button", "", "Yes");
    yes.type = "button";
    yes.dataset.answer = "yes";
    const no = element("button", "danger", "No");
    no.type = "button";
    no.dataset.answer = "no";
    box.append(text, yes, no);
    $(".tl-questions", entry).append(box);
    setBadge($(".badge-slot", entry), "waiting");
  }
}

/** Clicks on Yes/No. Wired once on the timeline list. */
export async function answerConfirmation(event) {
  const button = event.target.closest("button[data-answer]");
  if (!button) return;
  const box = button.closest(".tl-question");
  const status = $("#timeline-status");
  for (const b of box.querySelectorAll("button")) b.disabled = true;
  try {
    const response = await api(`/confirmations/${box.dataset.confirmation}`, { method: "POST", json: { answer: button.dataset.answer } });
    if (response.ok) {
      setStatus(status, `Answered ${button.dataset.answer}: ${$(".tl-question-text", box).textContent}`);
      box.remove();
    } else {
      setStatus(status, `Could not answer: ${await errorText(response)}`, "error");
      box.remove(); // settled elsewhere (expired, or answered by voice): the next poll shows the truth
    }
  } catch (error) {
    if (!(error instanceof SignedOut)) setStatus(status, "Could not answer: the kernel cannot be reached.", "error");
    for (const b of box.querySelectorAll("button")) b.disabled = false;
  }
}
