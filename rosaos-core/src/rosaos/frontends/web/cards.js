// Device cards drawn from the driver's declaration (rosaos.cards): a swatch, a gauge, a head, a
// pose, a camera frame, text. Every widget also says what it shows in words, for screen readers
// and for people who cannot tell colours apart.

import { colourName, swatchColour } from "./colours.js";
import { $, api } from "./session.js";

const SVG = "http://www.w3.org/2000/svg";
const FRAME_CHECK_MS = 2000;
const frames = new Map(); // device name -> { file, checked, url }

export function svg(tag, attributes = {}) {
  const element = document.createElementNS(SVG, tag);
  for (const [name, value] of Object.entries(attributes)) element.setAttribute(name, String(value));
  return element;
}

function element(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined) node.textContent = text;
  return node;
}

function setText(node, text) {
  if (node.textContent !== text) node.textContent = text;
}

const round = (value, digits = 2) => (typeof value === "number" ? value.toFixed(digits) : "—");
const degrees = (value) => (typeof value === "number" ? `${Math.round(value)}°` : "—");

/** A state value as text (objects as compact JSON). */
export function showValue(value) {
  if (value === null || value === undefined) return "—";
  if (typeof value === "number") return String(Number.isInteger(value) ? value : Math.round(value * 1000) / 1000);
  if (typeof value === "object") return JSON.stringify(value);
  return String(value);
}

// --- widgets: build(widget, device) makes the element once, update(node, widget, state, device) fills it

function labelled(widget) {
  const row = element("div", "widget-row");
  row.append(element("span", "widget-label", widget.label || widget.key), element("span", "widget-value"));
  return row;
}

const WIDGETS = {
  text: {
    build: labelled,
    update(node, widget, state) {
      const value = state[widget.key];
      setText($(".widget-value", node), value === null || value === "" ? "—" : `${showValue(value)}${widget.unit ? ` ${widget.unit}` : ""}`);
    },
  },
  flag: {
    build: labelled,
    update(node, widget, state) {
      const value = state[widget.key];
      setText($(".widget-value", node), value === null ? "—" : value ? widget.on_text : widget.off_text);
      node.dataset.on = String(Boolean(value));
    },
  },
  gauge: {
    build(widget) {
      const row = labelled(widget);
      const meter = element("meter");
      meter.min = widget.min;
      meter.max = widget.max;
      meter.setAttribute("aria-label", widget.label || widget.key);
      row.append(meter);
      return row;
    },
    update(node, widget, state) {
      const value = state[widget.key];
      const meter = $("meter", node);
      if (typeof value !== "number") {
        setText($(".widget-value", node), "—");
        meter.hidden = true;
        return;
      }
      meter.hidden = false;
      meter.value = value;
      // A "%" gauge shows the share of its range, so a 0-1 battery reads "87 %".
      const shown = widget.unit === "%" ? Math.round(((value - widget.min) / (widget.max - widget.min)) * 100) : round(value, 1);
      setText($(".widget-value", node), `${shown}${widget.unit ? ` ${widget.unit}` : ""}`);
      meter.setAttribute("aria-valuetext", `${shown} ${widget.unit}`.trim());
    },
  },
  swatch: {
    build() {
      const row = element("div", "widget-row swatch-row");
      const swatch = element("span", "swatch");
      swatch.setAttribute("role", "img");
      row.append(swatch, element("span", "swatch-name"));
      return row;
    },
    update(node, widget, state) {
      const k = widget.keys;
      const light = {
        on: Boolean(state[k.on]), brightness: state[k.brightness] ?? 100,
        hue: state[k.hue] ?? 0, saturation: state[k.saturation] ?? 0, colorTemp: state[k.color_temp] ?? 0,
      };
      const name = colourName(light);
      const text = light.on ? `${name}, ${light.brightness} %` : `off (${name} when on)`;
      const swatch = $(".swatch", node);
      swatch.style.background = swatchColour(light);
      swatch.setAttribute("aria-label", `Colour: ${text}`);
      setText($(".swatch-name", node), text);
      node.dataset.colour = light.on ? name : "off";
    },
  },
  pose: {
    build() {
      const row = element("div", "widget-row pose-row");
      const drawing = svg("svg", { viewBox: "-12 -12 24 24", width: 28, height: 28, "aria-hidden": "true", class: "pose-arrow" });
      drawing.append(svg("circle", { r: 11, class: "pose-ring" }), svg("path", { d: "M 9 0 L -6 -6 L -3 0 L -6 6 Z", class: "pose-pointer" }));
      row.append(drawing, element("span", "widget-value"));
      return row;
    },
    update(node, widget, state) {
      const k = widget.keys;
      const yaw = state[k.yaw];
      // Screen y grows downwards: a heading of +90° (left turn) points up.
      $(".pose-arrow path", node).setAttribute("transform", `rotate(${typeof yaw === "number" ? (-yaw * 180) / Math.PI : 0})`);
      const docked = state[k.docked] ? " · on its dock" : "";
      setText($(".widget-value", node), `x ${round(state[k.x])} m, y ${round(state[k.y])} m, heading ${degrees(typeof yaw === "number" ? (yaw * 180) / Math.PI : null)}${docked}`);
    },
  },
  head: { build: buildHead, update: updateHead },
  image: { build: buildFrame, update: updateFrame },
};

function buildHead() {
  const node = element("div", "head-widget");
  const drawing = svg("svg", { viewBox: "-60 -55 120 100", class: "head-drawing", role: "img" });
  const body = svg("g", { class: "head-body" });
  body.append(svg("path", { d: "M -34 44 Q -36 12 0 10 Q 36 12 34 44 Z", class: "robot-body" }));
  const head = svg("g", { class: "head" });
  head.append(
    svg("line", { class: "antenna antenna-left", x1: -14, y1: -22, x2: -14, y2: -50 }),
    svg("line", { class: "antenna antenna-right", x1: 14, y1: -22, x2: 14, y2: -50 }),
    svg("rect", { x: -30, y: -26, width: 60, height: 40, rx: 18, class: "robot-head" }),
    svg("circle", { cx: -12, cy: -6, r: 6, class: "robot-eye" }),
    svg("circle", { cx: 12, cy: -6, r: 6, class: "robot-eye" }),
  );
  drawing.append(body, head);
  node.append(drawing, element("p", "head-pose"), element("p", "head-said"));
  return node;
}

function updateHead(node, widget, state) {
  const k = widget.keys;
  const pose = state[k.head] || {};
  const [left = 0, right = 0] = Array.isArray(state[k.antennas]) ? state[k.antennas] : [];
  const yaw = Number(pose.yaw) || 0;
  const pitch = Number(pose.pitch) || 0;
  const roll = Number(pose.roll) || 0;
  const bodyYaw = Number(state[k.body_yaw]) || 0;
  // Seen from the front: the robot's left is our right, so a + yaw moves the head to our right.
  $(".head", node).setAttribute("transform", `translate(${yaw * 0.35} ${pitch * 0.35}) rotate(${roll})`);
  $(".head-body", node).setAttribute("transform", `translate(${bodyYaw * 0.15} 0)`);
  $(".antenna-left", node).setAttribute("transform", `rotate(${-left} -14 -22)`);
  $(".antenna-right", node).setAttribute("transform", `rotate(${right} 14 -22)`);
  node.dataset.awake = String(state[k.awake] !== false);
  const words = `Head yaw ${degrees(yaw)}, pitch ${degrees(pitch)}, roll ${degrees(roll)}; antennas ${degrees(left)} and ${degrees(right)}${state[k.awake] === false ? "; asleep" : ""}`;
  $(".head-drawing", node).setAttribute("aria-label", words);
  setText($(".head-pose", node), words);
  const said = state[k.said];
  setText($(".head-said", node), said ? `Last said: “${said}”` : "Has not spoken yet.");
}

function buildFrame() {
  const figure = element("figure", "frame");
  const wrap = element("div", "frame-wrap");
  const image = element("img");
  image.alt = "";
  image.hidden = true;
  wrap.append(image, svg("svg", { class: "frame-boxes", "aria-hidden": "true", preserveAspectRatio: "none" }));
  figure.append(wrap, element("figcaption", "frame-caption", "No picture yet."));
  return figure;
}

function updateFrame(node, widget, state, device) {
  const known = frames.get(device.name) || { file: null, checked: 0, url: null };
  frames.set(device.name, known);
  if (Date.now() - known.checked < FRAME_CHECK_MS) return;
  known.checked = Date.now();
  loadFrame(node, device.name, known).catch(() => { /* the next poll retries */ });
}

async function loadFrame(node, name, known) {
  const response = await api(`/devices/${encodeURIComponent(name)}/frame`);
  if (!response.ok) return;
  const info = await response.json();
  if (!info.file) return; // nothing captured yet: the caption says so
  const image = $("img", node);
  if (info.file !== known.file) {
    const picture = await api(`/devices/${encodeURIComponent(name)}/frames/${encodeURIComponent(info.file)}`);
    if (!picture.ok) return;
    const url = URL.createObjectURL(await picture.blob());
    await new Promise((resolve) => { image.onload = resolve; image.onerror = resolve; image.src = url; });
    if (known.url) URL.revokeObjectURL(known.url);
    known.url = url;
    known.file = info.file;
    image.hidden = false;
    node.dataset.file = info.file;
  }
  drawBoxes(node, info, image);
}

function drawBoxes(node, info, image) {
  const width = info.width || image.naturalWidth;
  const height = info.height || image.naturalHeight;
  const overlay = $(".frame-boxes", node);
  overlay.setAttribute("viewBox", `0 0 ${width} ${height}`);
  overlay.replaceChildren(...info.boxes.map((box) => {
    const group = svg("g", { class: "frame-box" });
    group.append(svg("rect", { x: box.x, y: box.y, width: box.width, height: box.height }));
    if (box.label) {
      const label = svg("text", { x: box.x + 3, y: Math.max(12, box.y - 4) });
      label.textContent = box.label;
      group.append(label);
    }
    return group;
  }));
  const found = info.boxes.length
    ? `; ${info.boxes.length} found by ${info.boxes_from}: ${info.boxes.map((b) => b.label || "unnamed").join(", ")}`
    : "";
  const when = new Date(info.time * 1000).toLocaleTimeString();
  const caption = `Last picture, ${when}${found}`;
  image.alt = `Last camera picture of ${info.device}, taken at ${when}${found}`;
  setText($(".frame-caption", node), caption);
  node.dataset.boxes = String(info.boxes.length);
}

/** Draw the declared widgets of one card in ``root``, reusing the elements made last time. */
export function renderCardView(root, device) {
  const widgets = device.card?.widgets || [];
  const state = device.state || {};
  root.hidden = widgets.length === 0;
  if (root.dataset.built !== String(widgets.length)) {
    root.replaceChildren(...widgets.map((widget) => {
      const node = WIDGETS[widget.kind]?.build(widget, device) || element("div");
      node.classList.add("widget");
      node.dataset.widgetKind = widget.kind;
      if (widget.key) node.dataset.widgetKey = widget.key;
      return node;
    }));
    root.dataset.built = String(widgets.length);
  }
  widgets.forEach((widget, index) => {
    const node = root.children[index];
    const kind = WIDGETS[widget.kind];
    // A key the driver left out hides its widget: a card must not show a made-up value.
    node.hidden = !kind || (widget.key && !(widget.key in state));
    if (!node.hidden) kind.update(node, widget, state, device);
  });
}
