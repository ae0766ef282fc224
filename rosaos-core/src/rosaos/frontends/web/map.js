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

// A robot reports positions in its own odometry frame, which starts wherever it was switched on;
// its config's map_origin ({x, y, yaw}) places that frame in the shared map.
function toMap(origin, x, y) {
  if (!origin) return [x, y];
  const c = Math.cos(origin.yaw || 0);
  const s = Math.sin(origin.yaw || 0);
  return [(origin.x || 0) + c * x - s * y, (origin.y || 0) + s * x + c * y];
}

function poseOf(device) {
  const widget = (device.card?.widgets || []).find((w) => w.kind === "pose");
  if (!widget) return null;
  const state = device.state || {};
  const k = widget.keys;
  if (typeof state[k.x] !== "number" || typeof state[k.y] !== "number") return null;
  const origin = device.map_origin || null;
  const people = (Array.isArray(state[k.people]) ? state[k.people] : [])
    .filter((p) => typeof p?.x === "number" && typeof p?.y === "number")
    .map((p) => { const [x, y] = toMap(origin, p.x, p.y); return { x, y }; });
  const [x, y] = toMap(origin, state[k.x], state[k.y]);
  const yaw = (Number(state[k.yaw]) || 0) + (origin?.yaw || 0);
  return { x, y, yaw, docked: state[k.docked] === true, people };
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
  for (const layer of layers.values()) points.push(...(layer.points?.() || []));
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

const PERSON_RADIUS = 0.7; // metres: sightings closer than this are one person

// People every robot has seen, merged: one marker per person, with how often they were seen.
function people() {
  const found = [];
  for (const [name, robot] of robots) {
    for (const seen of robot.people) {
      const same = found.find((p) => Math.hypot(p.x - seen.x, p.y - seen.y) < PERSON_RADIUS);
      if (same) {
        same.count += 1;
        same.by.add(name);
      } else {
        found.push({ x: seen.x, y: seen.y, count: 1, by: new Set([name]) });
      }
    }
  }
  return found;
}

// Labels never overprint: each takes the first free spot around its anchor, or is left out
// (a dock's or a person's label; a robot's name always finds a place further out).
function labelPlacer() {
  const taken = [];
  const font = 13 * (view.shrink || 1);
  const widthOf = (text, bold) => text.length * font * (bold ? 0.66 : 0.6) + 4;
  // The box of a <text> whose baseline is at y, anchored at x (start, middle or end).
  const box = (x, y, width, anchor) => {
    const left = anchor === "start" ? x : anchor === "end" ? x - width : x - width / 2;
    return { left, right: left + width, top: y - font, bottom: y + font * 0.3 };
  };
  const free = (b) => taken.every((t) => b.right < t.left || b.left > t.right || b.bottom < t.top || b.top > t.bottom);
  return {
    /** Keep the area of a marker clear of labels. */
    block(x, y, radius) { taken.push({ left: x - radius, right: x + radius, top: y - radius, bottom: y + radius }); },
    /** A <text> at the first free spot near (x, y), offset by ``gap`` pixels; null when none is free. */
    place(x, y, gap, text, className, required = false) {
      const step = font * 1.3;
      const width = widthOf(text, className === "map-label");
      // Above, below, right, left of the anchor; then the same, further out.
      const spots = [[0, -gap - font * 0.35], [0, gap + font * 1.05], [gap + 4, font * 0.35], [-gap - 4, font * 0.35]];
      for (let ring = 1; ring <= (required ? 6 : 1); ring += 1) {
        for (const [dx, dy] of spots) {
          const sx = x + Math.sign(dx) * (Math.abs(dx) + (ring - 1) * step * 2);
          const sy = y + Math.sign(dy) * (Math.abs(dy) + (ring - 1) * step);
          const anchor = dx > 0 ? "start" : dx < 0 ? "end" : "middle";
          const b = box(sx, sy, width, anchor);
          if (!free(b)) continue;
          taken.push(b);
          const node = svg("text", { x: sx.toFixed(1), y: sy.toFixed(1), class: className, "text-anchor": anchor });
          node.textContent = text;
          return node;
        }
      }
      return null;
    },
  };
}

function robotShape(name, robot, index, labels) {
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
  }
  const [sx, sy] = toScreen(robot.x, robot.y);
  // True size, within bounds that stay visible on screen however small the map is drawn.
  const radius = Math.min(14, Math.max(7, 0.17 * scale())) * (view.shrink || 1);
  const marker = svg("g", { class: "map-marker", transform: `translate(${sx.toFixed(1)} ${sy.toFixed(1)}) rotate(${(-robot.yaw * 180) / Math.PI})` });
  marker.append(svg("circle", { r: radius }), svg("path", { d: `M ${radius + 6} 0 L ${radius - 3} -6 L ${radius - 3} 6 Z`, class: "map-heading" }));
  group.append(marker);
  labels.block(sx, sy, radius + 6);
  return { group, sx, sy, radius };
}

function personShape(person, labels) {
  const [px, py] = toScreen(person.x, person.y);
  const mark = svg("g", { class: "map-person", "data-count": person.count, "data-seen-by": [...person.by].join(" ") });
  mark.append(svg("circle", { cx: px, cy: py - 6, r: 4 }), svg("path", { d: `M ${px - 7} ${py + 8} Q ${px} ${py - 4} ${px + 7} ${py + 8} Z` }));
  labels.block(px, py, 9);
  return { mark, px, py };
}

function describe(found) {
  const lines = [...robots].map(([name, r]) => {
    const where = `${name.replace(/_/g, " ")} at x ${r.x.toFixed(2)} m, y ${r.y.toFixed(2)} m, heading ${Math.round((r.yaw * 180) / Math.PI)}°`;
    return `${where}${r.docked ? ", docked" : ""}`;
  });
  if (found.length) lines.push(`${found.length} ${found.length === 1 ? "person" : "people"} seen`);
  for (const layer of layers.values()) lines.push(...(layer.summary?.() || []));
  return lines.join(". ");
}

// Extra layers (named places, a floor plan...): addMapLayer({ name, points, draw }) where
// points() gives [x, y] map metres to keep in view and draw(context) returns SVG nodes, drawn
// under the robots; summary(), if given, adds sentences to the map's text description. context: { toScreen, scale, shrink, svg, labels } (labels.place/block avoid overprinting).
const layers = new Map();

/** Add or replace a map layer; the map redraws on the next device poll. */
export function addMapLayer(layer) {
  layers.set(layer.name, layer);
}

function redraw() {
  const map = $("#floor-map");
  if (view.auto) fit();
  // The SVG scales with its box: on a phone, labels would shrink to a few pixels.
  const shrink = map.clientWidth ? WIDTH / map.clientWidth : 1;
  view.shrink = Math.max(1, shrink);
  map.style.setProperty("--map-font", `${Math.round(13 * view.shrink)}px`);
  const labels = labelPlacer();
  const names = [...robots.keys()];
  const shapes = names.map((name, index) => robotShape(name, robots.get(name), index, labels));
  const found = people();
  const persons = found.map((person) => personShape(person, labels));
  const context = { toScreen, scale: scale(), shrink: view.shrink, svg, labels };
  const extra = [...layers.values()].flatMap((layer) => {
    const group = svg("g", { class: `map-layer map-layer-${layer.name}` });
    group.append(...(layer.draw(context) || []));
    return [group];
  });
  const texts = svg("g", { class: "map-labels" });
  // Robots' names first: they always get a place; then docks and people where there is room.
  shapes.forEach(({ sx, sy, radius }, index) => {
    const node = labels.place(sx, sy, radius + 6, names[index].replace(/_/g, " "), "map-label", true);
    if (node) { node.dataset.labelOf = names[index]; texts.append(node); }
  });
  names.forEach((name) => {
    const dock = robots.get(name).dock;
    if (!dock) return;
    const [dx, dy] = toScreen(...dock);
    const node = labels.place(dx, dy, 14, `${name.replace(/_/g, " ")} dock`, "map-dock-label");
    if (node) texts.append(node);
  });
  persons.forEach(({ px, py }, index) => {
    const count = found[index].count;
    const node = labels.place(px, py, 14, count > 1 ? `person (seen ${count}×)` : "person", "map-person-label");
    if (node) texts.append(node);
  });
  map.replaceChildren(grid(), ...extra, ...shapes.map((s) => s.group), ...persons.map((p) => p.mark), texts);
  $("#map-summary").textContent = describe(found);
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

// Zooming from the fitted view centres on the robots, not on the middle of an empty map.
function zoom(factor) {
  if (view.auto && robots.size) {
    const xs = [...robots.values()].map((r) => r.x);
    const ys = [...robots.values()].map((r) => r.y);
    view.cx = (Math.min(...xs) + Math.max(...xs)) / 2;
    view.cy = (Math.min(...ys) + Math.max(...ys)) / 2;
  }
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
