// Controls on the device cards, as the driver declares them (rosaos.card_controls): a switch,
// sliders, a choice, buttons, a text box. Pressing one asks the kernel to launch a process that
// makes the call (POST /devices/NAME/controls/INDEX), so it is leased, logged and shown in
// Activity like any other, and refused while the emergency stop is latched: the card says why.

import { $, api, errorText, SignedOut } from "./session.js";
import { setMarkedText } from "./words.js";

const latch = { latched: false, reason: "" };

function element(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined) node.textContent = text;
  return node;
}

const shown = (control, state) =>
  Object.entries(control.shown_when || {}).every(([key, value]) => key in state && state[key] === value);

function build(control, index) {
  const node = element("div", `control control-${control.kind}`);
  node.dataset.controlIndex = String(index);
  node.dataset.controlKind = control.kind;
  if (control.kind === "toggle") {
    const button = element("button", "switch");
    button.type = "button";
    button.setAttribute("role", "switch");
    button.append(element("span", "switch-track"), element("span", "switch-label", control.label));
    node.append(button);
  } else if (control.kind === "button") {
    const button = element("button", "quiet", control.label);
    button.type = "button";
    node.append(button);
  } else if (control.kind === "slider") {
    const label = element("label", "control-slider-label");
    const input = element("input");
    Object.assign(input, { type: "range", min: control.min, max: control.max, step: control.step });
    label.append(element("span", "control-name", control.label), input, element("output", "control-output"));
    input.addEventListener("input", () => { $("output", node).textContent = `${input.value}${control.unit ? ` ${control.unit}` : ""}`; });
    node.append(label);
  } else if (control.kind === "choice") {
    const label = element("label", "control-choice-label");
    const select = element("select");
    select.append(new Option(`${control.label}…`, ""), ...control.options.map((option) => new Option(option, option)));
    label.append(element("span", "visually-hidden", control.label), select);
    node.append(label);
  } else if (control.kind === "prompt") {
    const form = element("form", "control-prompt");
    const input = element("input");
    Object.assign(input, { type: "text", maxLength: 500, placeholder: control.placeholder || "" });
    input.setAttribute("aria-label", `${control.label}: text`);
    const button = element("button", "quiet", control.label);
    button.type = "submit";
    form.append(input, button);
    node.append(form);
  }
  return node;
}

function update(node, control, state) {
  const value = control.key ? state[control.key] : undefined;
  if (control.kind === "toggle") {
    const on = value === true;
    const button = $("button", node);
    button.setAttribute("aria-checked", String(on));
    button.title = `${control.label}: ${on ? "on" : "off"}`;
  } else if (control.kind === "slider" && typeof value === "number") {
    const input = $("input", node);
    if (document.activeElement !== input && !node.dataset.sending) {
      input.value = String(value);
      $("output", node).textContent = `${Math.round(value)}${control.unit ? ` ${control.unit}` : ""}`;
    }
  }
}

/** Draw the controls of one card in ``root`` (once), show or hide them from the state, and say
 *  on the card when the emergency stop refuses them. */
export function renderControls(root, device) {
  const controls = device.card?.controls || [];
  const state = device.state || {};
  root.hidden = controls.length === 0;
  if (!controls.length) return;
  if (root.dataset.built !== String(controls.length)) {
    const list = element("div", "control-list");
    list.append(...controls.map(build));
    const note = element("p", "control-note");
    note.setAttribute("role", "note");
    const status = element("p", "control-status");
    status.setAttribute("role", "status");
    root.replaceChildren(list, note, status);
    root.dataset.built = String(controls.length);
    root.dataset.device = device.name;
    root._controls = controls;
    wire(root);
  }
  root._controls = controls;
  controls.forEach((control, index) => {
    const node = $(`[data-control-index="${index}"]`, root);
    node.hidden = !shown(control, state);
    if (!node.hidden) update(node, control, state);
  });
  showLatch(root);
}

function showLatch(root) {
  const note = $(".control-note", root);
  note.hidden = !latch.latched;
  setMarkedText(note, latch.latched
    ? `Controls are refused: the emergency stop is latched (${latch.reason}). Reset it at the top of the page first.`
    : "");
  root.dataset.latched = String(latch.latched);
}

/** The emergency stop's state, from its poll: every card says whether its controls are refused. */
export function controlsLatched(state) {
  latch.latched = Boolean(state.latched);
  latch.reason = state.reason || "";
  for (const root of document.querySelectorAll(".card-controls[data-built]")) showLatch(root);
}

function wire(root) {
  root.addEventListener("click", (event) => {
    const button = event.target.closest("button");
    const node = event.target.closest("[data-control-index]");
    if (!button || !node || button.type === "submit") return;
    const control = root._controls[Number(node.dataset.controlIndex)];
    const value = control.kind === "toggle" ? button.getAttribute("aria-checked") !== "true" : null;
    press(root, node, control, value);
  });
  root.addEventListener("change", (event) => {
    const node = event.target.closest("[data-control-index]");
    if (!node) return;
    const control = root._controls[Number(node.dataset.controlIndex)];
    if (control.kind === "slider") press(root, node, control, Number(event.target.value));
    else if (control.kind === "choice" && event.target.value) {
      press(root, node, control, event.target.value);
      event.target.value = "";
    }
  });
  root.addEventListener("submit", (event) => {
    event.preventDefault();
    const node = event.target.closest("[data-control-index]");
    const control = root._controls[Number(node.dataset.controlIndex)];
    const input = $("input", node);
    if (input.value.trim()) press(root, node, control, input.value.trim()).then((ok) => { if (ok) input.value = ""; });
  });
}

function said(control, value) {
  if (control.kind === "toggle") return `${control.label} ${value ? "on" : "off"}`;
  if (control.kind === "button") return control.label;
  if (control.kind === "prompt") return `${control.label}: “${value}”`;
  return `${control.label} ${value}${control.unit ? ` ${control.unit}` : ""}`;
}

async function press(root, node, control, value) {
  const status = $(".control-status", root);
  status.dataset.kind = "info";
  status.textContent = `${said(control, value)}…`;
  node.dataset.sending = "1";
  try {
    const device = encodeURIComponent(root.dataset.device);
    const response = await api(`/devices/${device}/controls/${node.dataset.controlIndex}`, { method: "POST", json: { value } });
    if (response.ok) {
      const body = await response.json();
      status.textContent = `${said(control, value)}: sent (process ${body.process_id}).`;
      return true;
    }
    status.dataset.kind = "error";
    setMarkedText(status, `${said(control, value)} refused: ${await errorText(response)}`);
  } catch (error) {
    if (error instanceof SignedOut) return false;
    status.dataset.kind = "error";
    status.textContent = `${said(control, value)} not sent: the kernel cannot be reached.`;
  } finally {
    delete node.dataset.sending;
  }
  return false;
}
