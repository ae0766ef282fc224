// The processes table and the device cards, redrawn in place from polled JSON.

import { renderCardView, showValue } from "./cards.js";
import { drawMap } from "./map.js";
import { $, api, errorText, setBadge, setStatus, SignedOut, timeOf } from "./session.js";
import { taskTitle } from "./timeline.js";

export function renderProcesses(processes) {
  const root = $("#processes");
  const table = $("table", root);
  const body = $("tbody", table);
  $("[data-empty]", root).hidden = processes.length > 0;
  table.hidden = processes.length === 0;
  const wanted = new Set(processes.map((p) => String(p.id)));
  for (const row of [...body.rows]) if (!wanted.has(row.dataset.process)) row.remove();
  for (const process of processes) {
    let row = $(`tr[data-process="${process.id}"]`, body);
    if (!row) {
      row = body.insertRow();
      row.dataset.process = process.id;
      for (const name of ["id", "task", "devices", "state", "started"]) row.insertCell().className = `cell-${name}`;
      const button = document.createElement("button");
      button.type = "button";
      button.className = "danger";
      button.dataset.terminate = process.id;
      button.textContent = "Terminate";
      button.setAttribute("aria-label", `Terminate process ${process.id}`);
      row.insertCell().append(button);
    }
    row.cells[0].textContent = process.id;
    row.cells[1].textContent = taskTitle(process.task);  // the plan block is for the worker, not people
    row.cells[1].title = process.task || "";
    row.cells[2].textContent = (process.devices || []).join(", ") || "—";
    setBadge(row.cells[3], process.state);
    row.cells[4].textContent = process.started_at ? timeOf(process.started_at) : "";
    $("button", row.cells[5]).hidden = process.state !== "running";
  }
}

export async function terminate(button) {
  const id = button.dataset.terminate;
  button.disabled = true;
  const status = $("#chat-status");
  try {
    const response = await api(`/processes/${id}/terminate`, { method: "POST" });
    if (!response.ok) setStatus(status, `Could not terminate process ${id}: ${await errorText(response)}`, "error");
    else setStatus(status, `Process ${id} terminated.`);
  } catch (error) {
    if (!(error instanceof SignedOut)) setStatus(status, `Could not terminate process ${id}: kernel unreachable.`, "error");
  } finally {
    button.disabled = false;
  }
}

export function renderDevices(devices) {
  const root = $("#devices");
  $(".empty", root)?.remove();
  const wanted = new Set(devices.map((d) => d.name));
  for (const card of root.querySelectorAll(".device-card")) if (!wanted.has(card.dataset.device)) card.remove();
  if (!devices.length) root.innerHTML = '<p class="empty">No devices are configured.</p>';
  for (const device of devices) {
    let card = root.querySelector(`.device-card[data-device="${CSS.escape(device.name)}"]`);
    if (!card) {
      card = document.createElement("article");
      card.className = "device-card";
      card.dataset.device = device.name;
      card.innerHTML = '<header><h3></h3><span class="badge-slot"></span></header>' +
        '<p class="meta"></p><p class="description"></p><div class="card-view"></div>' +
        '<details class="raw"><summary>Details</summary><dl></dl></details>';
      $("h3", card).textContent = device.name;
      card.setAttribute("aria-label", `Device ${device.name}`);
      root.append(card);
    }
    setBadge($(".badge-slot", card), device.status);
    $(".meta", card).textContent = [device.driver, device.backend, device.concurrency].filter(Boolean).join(" · ");
    $(".description", card).textContent = device.description || "";
    renderCardView($(".card-view", card), device);
    // Without a declared card the raw state is the card: show it open.
    const raw = $("details.raw", card);
    if (!device.card && !raw.dataset.touched) raw.open = true;
    raw.ontoggle ??= () => { raw.dataset.touched = "1"; };
    renderState($("dl", card), device.state || {});
  }
  drawMap(devices);
}

function renderState(list, state) {
  for (const row of [...list.children]) if (!(row.dataset.row in state)) row.remove();
  for (const key of Object.keys(state)) {
    let row = [...list.children].find((child) => child.dataset.row === key);
    if (!row) {
      row = document.createElement("div");
      row.dataset.row = key;
      const term = document.createElement("dt");
      term.textContent = key;
      const value = document.createElement("dd");
      value.dataset.key = key;
      row.append(term, value);
      list.append(row);
    }
    const text = showValue(state[key]);
    const value = $("dd", row);
    if (value.textContent !== text) value.textContent = text;
  }
}
