// Words for people: a tool result as one readable line, a call as "Kitchen light: set colour",
// and server text with `code` marks drawn as code rather than shown with its backticks.

import { colourName } from "./colours.js";

const MAX_CHARS = 140;

/** "kitchen_light" -> "kitchen light". */
export const spaced = (name) => String(name ?? "").replace(/_/g, " ");
/** "kitchen_light" -> "Kitchen light". */
export const titled = (name) => { const text = spaced(name); return text.charAt(0).toUpperCase() + text.slice(1); };

function cut(text) {
  const line = String(text).replace(/\s+/g, " ").trim();
  return line.length > MAX_CHARS ? `${line.slice(0, MAX_CHARS - 1)}…` : line;
}

const PAIR = /"(\w+)"\s*:\s*("(?:[^"\\]|\\.)*"|-?\d+(?:\.\d+)?|true|false)/g;

// Receipts carry results as JSON text, cut when long: a cut one is read pair by pair.
function parsed(text) {
  if (typeof text !== "string") return text;
  try { return JSON.parse(text); } catch (_) { /* cut, or plain text */ }
  if (!/^\s*[[{]/.test(text)) return text;
  const pairs = {};
  for (const [, key, value] of text.matchAll(PAIR)) {
    try { pairs[key] = JSON.parse(value); } catch (_) { /* a cut string: leave it out */ }
  }
  return pairs;
}

function scalar(value) {
  if (value === true) return "yes";
  if (value === false) return "no";
  if (typeof value === "number") return String(Number.isInteger(value) ? value : Math.round(value * 100) / 100);
  return typeof value === "string" ? value : null;
}

/** A tool's result (JSON text as the receipts carry it) as one line: the driver's own words when it
 *  has some (message, detail, summary...), a lamp as its card names it, else a few "key value" pairs. */
export function resultLine(raw) {
  const value = parsed(raw);
  if (value === null || value === undefined || value === "") return "";
  if (typeof value !== "object") return cut(scalar(value) ?? "");
  if (Array.isArray(value)) return `${value.length} ${value.length === 1 ? "item" : "items"}`;
  for (const key of ["message", "detail", "summary", "said", "status_text", "text"]) {
    if (typeof value[key] === "string" && value[key].trim()) return cut(value[key]);
  }
  if ("on" in value && ("hue" in value || "brightness" in value)) {
    const light = {
      on: Boolean(value.on), brightness: value.brightness ?? 100, hue: value.hue ?? 0,
      saturation: value.saturation ?? 0, colorTemp: value.color_temp ?? 0,
    };
    return light.on ? `on, ${colourName(light)}, ${light.brightness} %` : "off";
  }
  const pairs = [];
  for (const [key, item] of Object.entries(value)) {
    const text = scalar(item);
    if (text !== null && text !== "") pairs.push(`${spaced(key)} ${text}`);
    if (pairs.length === 4) break;
  }
  return cut(pairs.join(", "));
}

/** One tool call in words: "Kitchen light: set color name (red)". */
export function callLine(receipt) {
  const args = Object.values(receipt.arguments || {}).map((v) => scalar(v) ?? "…").filter(Boolean);
  return `${titled(receipt.device)}: ${spaced(receipt.tool)}${args.length ? ` (${cut(args.join(", "))})` : ""}`;
}

/** Fill ``node`` with ``text``, drawing `marked` parts as <code> instead of showing the backticks. */
export function setMarkedText(node, text) {
  const parts = String(text ?? "").split("`");
  node.replaceChildren(...parts.map((part, index) => {
    if (index % 2 === 0) return document.createTextNode(part.replace(/\*\*|__/g, ""));
    const code = document.createElement("code");
    code.textContent = part;
    return code;
  }));
}

/** Sentences a person could type to the devices of this world, from what their cards draw. */
export function suggestions(devices) {
  const found = [];
  for (const device of devices) {
    const kinds = new Set((device.card?.widgets || []).map((w) => w.kind));
    const keys = new Set((device.card?.widgets || []).map((w) => w.key));
    const state = device.state || {};
    const name = spaced(device.name);
    if (kinds.has("swatch")) found.push(`Turn the ${name} green`);
    else if (kinds.has("pose")) found.push("docked" in state ? `Undock the ${name}` : `Make the ${name} walk forward`);
    else if (kinds.has("head")) found.push(`Make the ${name} say hello`);
    else if (keys.has("volume")) found.push("Play some jazz");
  }
  return [...new Set(found)];
}
