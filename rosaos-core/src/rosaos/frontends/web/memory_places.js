// The named places under the floor map, each with Rename and Delete: PATCH and DELETE
// /places/{name}, the same rules as `rosaos places rename` and `delete`. The kernel checks every
// name (unknown place, empty, too long, taken) and its message is shown as it says it.

import { $, api, errorText, setStatus, SignedOut } from "./session.js";
import { renderPlaces } from "./memory_map.js";

const NAME_MAX = 80; // rosaos.memory.store.NAME_MAX; the kernel refuses longer names anyway
let drawn = null; // the names last drawn: the list is rebuilt only when they change

/** GET /places: list them, unless a rename is being typed (a poll must not wipe the input). */
export function listPlaces(body) {
  const names = (body.places || []).map((place) => place.name);
  const list = $("#places");
  if (list.querySelector("form") || names.join("\n") === drawn) return;
  drawn = names.join("\n");
  list.replaceChildren(...names.map(placeItem));
}

function button(text, action, label, kind = "quiet") {
  const node = document.createElement("button");
  node.type = "button";
  node.className = kind;
  node.textContent = text;
  node.dataset.action = action;
  node.setAttribute("aria-label", label);
  return node;
}

function placeItem(name) {
  const item = document.createElement("li");
  item.dataset.place = name;
  const label = document.createElement("span");
  label.className = "place-name";
  label.textContent = name;
  item.append(label, button("Rename", "rename", `Rename ${name}`), button("Delete", "delete", `Delete ${name}`, "danger"));
  return item;
}

function renameForm(name) {
  const form = document.createElement("form");
  form.className = "place-rename";
  const input = document.createElement("input");
  input.name = "name";
  input.value = name;
  input.maxLength = NAME_MAX;
  input.setAttribute("aria-label", `New name for ${name}`);
  const save = document.createElement("button");
  save.type = "submit";
  save.textContent = "Save";
  form.append(input, save, button("Cancel", "cancel", "Cancel renaming"));
  return form;
}

async function refresh() {
  const response = await api("/places");
  if (!response.ok) return;
  const body = await response.json();
  drawn = null;
  renderPlaces(body);
  listPlaces(body);
}

async function change(path, options, done) {
  const status = $("#places-status");
  try {
    const response = await api(path, options);
    if (!response.ok) {
      setStatus(status, `Not changed: ${await errorText(response)}`, "error");
      return false;
    }
    setStatus(status, done);
    return true;
  } catch (error) {
    if (!(error instanceof SignedOut)) setStatus(status, "Not changed: the kernel cannot be reached. Try again.", "error");
    return false;
  }
}

/** Clicks in the list: Rename opens a small form, Delete deletes, Cancel closes the form. */
export async function placeClicked(event) {
  const target = event.target.closest("button[data-action]");
  if (!target) return;
  const item = target.closest("li[data-place]");
  const name = item.dataset.place;
  if (target.dataset.action === "rename") {
    const form = renameForm(name);
    item.replaceChildren(form);
    form.elements.name.select();
  } else if (target.dataset.action === "cancel") {
    item.replaceWith(placeItem(name));
  } else if (target.dataset.action === "delete") {
    target.disabled = true;
    const path = `/places/${encodeURIComponent(name)}`;
    if (!(await change(path, { method: "DELETE" }, `Deleted ${name}.`))) target.disabled = false;
    await refresh();
  }
}

/** Save in a rename form: PATCH /places/{name}; on a refusal the form stays, with the reason. */
export async function placeRenamed(event) {
  event.preventDefault();
  const form = event.target;
  const name = form.closest("li[data-place]").dataset.place;
  const wanted = form.elements.name.value;
  const path = `/places/${encodeURIComponent(name)}`;
  if (await change(path, { method: "PATCH", json: { name: wanted } }, `Renamed ${name} to ${wanted.trim()}.`)) {
    form.remove();
    await refresh();
  }
}
