// What rosaOS remembers, on the floor map: the named places (GET /places) and where the robots
// saw someone (GET /sightings). Both keep the frame of the robot that saved or saw them, so each is
// drawn where that robot's own pose is drawn (its map_origin). Sightings fade with age over the
// keep window ([memory] sightings_days); sightings of one spot are merged and the newest is told.

import { addMapLayer } from "./map.js";

const SAME_SPOT = 0.7; // metres: sightings closer than this are drawn as one
const FADED = 0.3; // opacity of a sighting at the end of the keep window
const origins = new Map(); // device -> map_origin ({x, y, yaw}) or null
const memory = { places: [], sightings: [], now: 0, keepDays: 7 };

function toMap(device, x, y) {
  const origin = origins.get(device);
  if (!origin) return [x, y];
  const c = Math.cos(origin.yaw || 0);
  const s = Math.sin(origin.yaw || 0);
  return [(origin.x || 0) + c * x - s * y, (origin.y || 0) + s * x + c * y];
}

/** How long ago, in words: "just now", "4 minutes ago", "2 hours ago", "3 days ago". */
export function ago(seconds) {
  for (const [unit, size] of [["day", 86400], ["hour", 3600], ["minute", 60]]) {
    if (seconds >= size) {
      const count = Math.floor(seconds / size);
      return `${count} ${unit}${count === 1 ? "" : "s"} ago`;
    }
  }
  return "just now";
}

function located(items) {
  return items.filter((item) => typeof item.x === "number" && typeof item.y === "number");
}

// One marker per spot, newest first (the list comes newest first).
function spots() {
  const merged = [];
  for (const seen of located(memory.sightings)) {
    const [x, y] = toMap(seen.device, seen.x, seen.y);
    const same = merged.find((spot) => Math.hypot(spot.x - x, spot.y - y) < SAME_SPOT);
    if (same) same.count += 1;
    else merged.push({ ...seen, x, y, count: 1, age: Math.max(0, memory.now - seen.at) });
  }
  return merged;
}

function sightingText(spot) {
  const where = spot.place ? ` in ${spot.place}` : "";
  return `${spot.what}${where}, ${ago(spot.age)}, seen by ${spot.device.replace(/_/g, " ")}`;
}

function draw({ toScreen, svg, labels, shrink }) {
  const nodes = [];
  for (const place of located(memory.places)) {
    const [px, py] = toScreen(...toMap(place.device, place.x, place.y));
    const size = 7 * shrink;
    const mark = svg("g", { class: "map-place", "data-place": place.name });
    mark.append(svg("path", { d: `M ${px} ${py - size} L ${px + size} ${py} L ${px} ${py + size} L ${px - size} ${py} Z` }));
    const title = svg("title", {});
    title.textContent = `${place.name} (saved by ${place.device.replace(/_/g, " ")})`;
    mark.append(title);
    labels.block(px, py, size + 2);
    const label = labels.place(px, py, size + 6, place.name, "map-place-label", true);
    if (label) mark.append(label);
    nodes.push(mark);
  }
  const keep = memory.keepDays * 86400;
  spots().forEach((spot, index) => {
    const [sx, sy] = toScreen(spot.x, spot.y);
    const opacity = Math.max(FADED, 1 - (1 - FADED) * (spot.age / keep));
    const mark = svg("g", {
      class: "map-sighting",
      opacity: opacity.toFixed(2),
      "data-device": spot.device,
      "data-place": spot.place || "",
      "data-at": String(spot.at),
      "data-count": String(spot.count),
      "data-x": spot.x.toFixed(3),
      "data-y": spot.y.toFixed(3),
    });
    const r = 6 * shrink;
    mark.append(svg("circle", { cx: sx, cy: sy, r }), svg("circle", { cx: sx, cy: sy, r: r / 3, class: "map-sighting-dot" }));
    const title = svg("title", {});
    title.textContent = sightingText(spot) + (spot.count > 1 ? ` (seen ${spot.count}× here)` : "");
    mark.append(title);
    labels.block(sx, sy, r + 2);
    // The newest gets its words on the map; older ones say them on hover and in the summary.
    const label = index === 0 ? labels.place(sx, sy, r + 6, `seen ${ago(spot.age)}`, "map-sighting-label") : null;
    if (label) mark.append(label);
    nodes.push(mark);
  });
  return nodes;
}

function points() {
  return [
    ...located(memory.places).map((p) => toMap(p.device, p.x, p.y)),
    ...spots().map((s) => [s.x, s.y]),
  ];
}

function summary() {
  const lines = [];
  const named = located(memory.places).map((p) => p.name);
  if (named.length) lines.push(`Places: ${named.join(", ")}`);
  const newest = spots()[0];
  if (newest) lines.push(`Last seen: ${sightingText(newest)}`);
  return lines;
}

addMapLayer({ name: "memory", points, draw, summary });

/** Note each device's map_origin (from GET /devices): places and sightings are drawn in it. */
export function noteOrigins(devices) {
  origins.clear();
  for (const device of devices) origins.set(device.name, device.map_origin || null);
}

/** GET /places. */
export function renderPlaces(body) {
  memory.places = body.places || [];
}

/** GET /sightings. */
export function renderSightings(body) {
  memory.sightings = body.sightings || [];
  memory.now = body.now || Date.now() / 1000;
  memory.keepDays = body.keep_days || memory.keepDays;
}
