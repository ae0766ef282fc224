// The floor map: every device whose card has a pose widget, seen from above, with its heading,
// the trail it drove, its dock and the people its camera found. World metres, x to the right and
// y up (ROS's convention). It fits itself to what it shows until the user pans or zooms; "Fit"
// goes back to that. Drag or use the arrow keys to pan, + and - to zoom, 0 to fit.

import { svg } from "./cards.js";
import { $ } from "./session.js";

const WIDTH = 640;
const HEIGHT = 380;
const TRAIL_POINTS = 300;
const TRAIL_STEP = 0.02; // metres between kept trail points
const MIN_SPAN = 4; // metres: the map never zooms in further than this when fitting
const robots = new Map(); // name -> { x, y, yaw, docked, trail, dock, people }
const view = { auto: true, cx: 0, cy: 0, span: MIN_SPAN, shrink: 1 };

function poseOf(device) {
  const widget = (device.card?.widgets || []).find((w) => w.kind === "pose");
  if (!widget) return null;
  const state = device.state || {};
  const k = widget.keys;
  if (typeof state[k.x] !== "number" || typeof state[k.y] !== "number") return null;
  const people = Array.isArray(state[k.people]) ? state[k.people].filter((p) => typeof p?.x === "number" && typeof p?.y === "number") : [];
  return { x: state[k.x], y: state[k.y], yaw: Number(state[k.yaw]) || 0, docked: state[k.docked] === true, people };
}

function remember(name, pose) {
  const robot = robots.get(name) || { trail: [], dock: null };
  Object.assign(robot, pose);
  const last = robot.trail[robot.trail.length - 1];
  if (!last || Math.hypot(last[0] - pose.x, last[1] - pose.y) >= TRAIL_STEP) {
    robot.trail.push([pose.x, pose.y]);
    if (robot.trail.length > TRAIL_POINTS) robot.trail.shift();
  }
  // The dock is where the robot was last seen docked: the state says whether, not where.
  if (pose.docked) robot.dock = [pose.x, pose.y];
  robots.set(name, robot);
}

function fit() {
  const points = [];
  for (const robot of robots.values()) {
    points.push([robot.x, robot.y], ...robot.trail, ...robot.people.map((p) => [p.x, p.y]));
    if (robot.dock) points.push(robot.dock);
  }
  if (!points.length) return;
  const xs = points.map((p) => p[0]);
  const ys = points.map((p) => p[1]);
  const [minX, maxX, minY, maxY] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  view.cx = (minX + maxX) / 2;
  view.cy = (minY + maxY) / 2;
  view.span = Math.max(MIN_SPAN, (maxX - minX) + 1.5, ((maxY - minY) + 1.5) * (WIDTH / HEIGHT));
}

// World metres to map pixels.
function scale() { return WIDTH / view.span; }
function toScreen(x, y) {
  return [WIDTH / 2 + (x - view.cx) * scale(), HEIGHT / 2 - (y - view.cy) * scale()];
}

function grid() {
  const group = svg("g", { class: "map-grid" });
  const step = view.span > 30 ? 5 : view.span > 12 ? 2 : 1;
  const halfW = view.span / 2;
  const halfH = halfW * (HEIGHT / WIDTH);
  for (let x = Math.ceil((view.cx - halfW) / step) * step; x <= view.cx + halfW; x += step) {
    const [sx] = toScreen(x, 0);
    group.append(svg("line", { x1: sx, y1: 0, x2: sx, y2: HEIGHT, class: x === 0 ? "axis" : "" }));
  }
  for (let y = Math.ceil((view.cy - halfH) / step) * step; y <= view.cy + halfH; y += step) {
    const [, sy] = toScreen(0, y);
    group.append(svg("line", { x1: 0, y1: sy, x2: WIDTH, y2: sy, class: y === 0 ? "axis" : "" }));
  }
  const bar = svg("g", { class: "map-scale" });
  bar.append(svg("line", { x1: 12, y1: HEIGHT - 14, x2: 12 + step * scale(), y2: HEIGHT - 14 }));
  const label = svg("text", { x: 14, y: HEIGHT - 20 });
  label.textContent = `${step} m`;
  bar.append(label);
  group.append(bar);
  return group;
}

function label(x, y, text, className) {
  const node = svg("text", { x, y, class: className, "text-anchor": "middle" });
  node.textContent = text;
  return node;
}

function robotGroup(name, robot, index) {
  const group = svg("g", { class: `map-robot hue-${index % 4}`, "data-robot": name });
  group.dataset.x = robot.x.toFixed(3);
  group.dataset.y = robot.y.toFixed(3);
  if (robot.trail.length > 1) {
    const points = robot.trail.map(([x, y]) => toScreen(x, y).map((v) => v.toFixed(1)).join(",")).join(" ");
    group.append(svg("polyline", { points, class: "map-trail" }));
  }
  if (robot.dock) {
    const [dx, dy] = toScreen(...robot.dock);
    group.append(svg("rect", { x: dx - 9, y: dy - 9, width: 18, height: 18, class: "map-dock" }));
    group.append(label(dx, dy + 22, `${name} dock`, "map-dock-label"));
  }
  for (const person of robot.people) {
    const [px, py] = toScreen(person.x, person.y);
    const mark = svg("g", { class: "map-person", "data-person-of": name });
    mark.append(svg("circle", { cx: px, cy: py - 6, r: 4 }), svg("path", { d: `M ${px - 7} ${py + 8} Q ${px} ${py - 4} ${px + 7} ${py + 8} Z` }));
    group.append(mark, label(px, py + 20, "person", "map-person-label"));
  }
  const [sx, sy] = toScreen(robot.x, robot.y);
  // True size, within bounds that stay visible on screen however small the map is drawn.
  const radius = Math.min(14, Math.max(7, 0.17 * scale())) * (view.shrink || 1);
  const marker = svg("g", { class: "map-marker", transform: `translate(${sx.toFixed(1)} ${sy.toFixed(1)}) rotate(${(-robot.yaw * 180) / Math.PI})` });
  marker.append(svg("circle", { r: radius }), svg("path", { d: `M ${radius + 6} 0 L ${radius - 3} -6 L ${radius - 3} 6 Z`, class: "map-heading" }));
  group.append(marker, label(sx, sy - radius - 6, name, "map-label"));
  return group;
}

function describe() {
  const lines = [...robots].map(([name, r]) => {
    const people = r.people.length ? `; ${r.people.length} ${r.people.length === 1 ? "person" : "people"} seen` : "";
    const where = `${name} at x ${r.x.toFixed(2)} m, y ${r.y.toFixed(2)} m, heading ${Math.round((r.yaw * 180) / Math.PI)}°`;
    return `${where}${r.docked ? ", docked" : ""}${people}`;
  });
  return lines.join(". ");
}

function redraw() {
  const map = $("#floor-map");
  if (view.auto) fit();
  // The SVG scales with its box: on a phone, labels would shrink to a few pixels.
  const shrink = map.clientWidth ? WIDTH / map.clientWidth : 1;
  view.shrink = Math.max(1, shrink);
  map.style.setProperty("--map-font", `${Math.round(13 * view.shrink)}px`);
  const names = [...robots.keys()];
  map.replaceChildren(grid(), ...names.map((name, index) => robotGroup(name, robots.get(name), index)));
  $("#map-summary").textContent = describe();
}

/** Update the map from the polled device list. */
export function drawMap(devices) {
  const panel = $("#map-panel");
  let seen = 0;
  for (const device of devices) {
    const pose = poseOf(device);
    if (!pose) continue;
    seen += 1;
    remember(device.name, pose);
  }
  for (const name of robots.keys()) if (!devices.some((d) => d.name === name)) robots.delete(name);
  panel.hidden = seen === 0 && robots.size === 0;
  if (!panel.hidden) redraw();
}

function zoom(factor) {
  view.auto = false;
  view.span = Math.min(500, Math.max(0.5, view.span * factor));
  redraw();
}

function pan(dx, dy) {
  view.auto = false;
  view.cx += dx * view.span;
  view.cy += dy * view.span;
  redraw();
}

/** Buttons, keyboard and dragging. Called once. */
export function wireMap() {
  const map = $("#floor-map");
  map.setAttribute("viewBox", `0 0 ${WIDTH} ${HEIGHT}`);
  $("#map-zoom-in").addEventListener("click", () => zoom(1 / 1.5));
  $("#map-zoom-out").addEventListener("click", () => zoom(1.5));
  $("#map-fit").addEventListener("click", () => { view.auto = true; redraw(); });
  map.addEventListener("keydown", (event) => {
    const moves = { ArrowLeft: [-0.1, 0], ArrowRight: [0.1, 0], ArrowUp: [0, 0.1], ArrowDown: [0, -0.1] };
    if (moves[event.key]) pan(...moves[event.key]);
    else if (event.key === "+" || event.key === "=") zoom(1 / 1.5);
    else if (event.key === "-") zoom(1.5);
    else if (event.key === "0") { view.auto = true; redraw(); }
    else return;
    event.preventDefault();
  });
  let drag = null;
  map.addEventListener("pointerdown", (event) => { drag = { x: event.clientX, y: event.clientY }; map.setPointerCapture(event.pointerId); });
  map.addEventListener("pointerup", () => { drag = null; });
  map.addEventListener("pointermove", (event) => {
    if (!drag) return;
    const metresPerPixel = view.span / map.clientWidth;
    view.auto = false;
    view.cx -= (event.clientX - drag.x) * metresPerPixel;
    view.cy += (event.clientY - drag.y) * metresPerPixel;
    drag = { x: event.clientX, y: event.clientY };
    redraw();
  });
}
