// The device cards, redrawn in place from polled JSON.

import { renderCardView, showValue } from "./cards.js";
import { renderControls } from "./controls.js";
import { drawMap } from "./map.js";
import { $, setBadge } from "./session.js";
import { spaced, titled } from "./words.js";

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
        '<div class="card-controls"></div><p class="card-busy" hidden></p>' +
        '<details class="raw"><summary>Details</summary><p class="tech"></p><dl></dl></details>';
      $("h3", card).textContent = titled(device.name);
      card.setAttribute("aria-label", `Device ${device.name}`);
      root.append(card);
    }
    setBadge($(".badge-slot", card), device.status);
    $(".meta", card).textContent = kindWords(device);
    $(".description", card).textContent = device.description || "";
    $(".tech", card).textContent = `Driver ${device.driver}, ${device.backend || "sim"} backend, ${device.concurrency} use, instance ${device.name}`;
    renderCardView($(".card-view", card), device);
    renderControls($(".card-controls", card), device);
    const busy = $(".card-busy", card);
    busy.hidden = !(device.held_by || []).length;
    busy.textContent = busy.hidden ? "" : `In use by process ${device.held_by.join(", ")} (see Running now).`;
    // Without a declared card the raw state is the card: show it open.
    const raw = $("details.raw", card);
    if (!device.card && !raw.dataset.touched) raw.open = true;
    raw.ontoggle ??= () => { raw.dataset.touched = "1"; };
    renderState($("dl", card), device.state || {});
  }
  drawMap(devices);
}

/** "simulated lamp": what the device is, in words, from its card (the driver's noun). */
function kindWords(device) {
  const noun = device.card?.noun || spaced(device.driver);
  if (device.backend === "sim") return `simulated ${noun}`;
  return device.backend === "real" ? noun : `${noun} (${device.backend || "remote"})`;
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
