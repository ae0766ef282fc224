// rosaOS web page: chat with the kernel, follow its updates, watch processes and devices.
// Plain JavaScript modules, no framework, no build step. Every value from the server is shown
// with textContent, never parsed as HTML.

import { renderDevices } from "./panels.js";
import { renderRunning, stopProcess } from "./running.js";
import {
  $, api, errorText, login, newKey, page, setConnection, setStatus, signOut, SignedOut, sleep, takeLoginCode,
} from "./session.js";
import { followUpdates, showChatDetails } from "./stream.js";
import { renderEmergencyStop, wireEmergencyStop } from "./estop.js";
import { wireMap } from "./map.js";
import { noteOrigins, renderPlaces, renderSightings } from "./memory_map.js";
import { listPlaces, placeClicked, placeRenamed } from "./memory_places.js";
import { cancelTimer, detectTimers } from "./timers.js";
import { answerConfirmation, renderConfirmations, timelineProcesses } from "./timeline.js";
import { setMarkedText, suggestions } from "./words.js";

const POLL_MS = 1000;

async function sendChat(event) {
  event.preventDefault();
  const input = $("#chat-input");
  const button = $("#chat-send");
  const status = $("#chat-status");
  const text = input.value.trim();
  if (!text) {
    setStatus(status, "Type a message first.", "error");
    input.focus();
    return;
  }
  button.disabled = true;
  setStatus(status, "Sending…");
  // One key per message: a retry after a network error cannot enqueue it twice.
  const body = { text, idempotency_key: newKey(), source: "web" };
  try {
    for (let attempt = 1; ; attempt += 1) {
      try {
        const response = await api("/chat", { method: "POST", json: body });
        if (response.status === 202) {
          input.value = "";
          setStatus(status, "");
        } else {
          setStatus(status, `Not sent: ${await errorText(response)}`, "error");
        }
        break;
      } catch (error) {
        if (error instanceof SignedOut || attempt === 3) throw error;
        await sleep(500 * attempt);
      }
    }
  } catch (error) {
    if (!(error instanceof SignedOut)) setStatus(status, "Not sent: the kernel cannot be reached. Try again.", "error");
  } finally {
    button.disabled = false;
    input.focus();
  }
}

async function pollForever(path, render) {
  while (page.running) {
    if (!document.hidden) {
      try {
        const response = await api(path);
        if (response.ok) render(await response.json());
      } catch (error) {
        if (error instanceof SignedOut) return;
        if (!(error instanceof TypeError && /fetch/i.test(error.message))) console.error(`drawing ${path} failed:`, error);
      }
    }
    await sleep(POLL_MS);
  }
}

async function showHealth() {
  try {
    const response = await fetch("/health", { cache: "no-store" });
    const health = await response.json();
    $("#model-name").textContent = health.model;
    const notice = $("#model-notice");
    page.modelNotice = health.model_notice || "";
    setMarkedText(notice, page.modelNotice);
    notice.hidden = !health.model_notice;
  } catch (_) {
    setConnection("offline", "The kernel cannot be reached");
  }
}

// The chat box and the offline banner suggest sentences for the devices of this world.
function suggest(devices) {
  const examples = suggestions(devices);
  if (!examples.length || page.suggested === examples.join("|")) return;
  page.suggested = examples.join("|");
  $("#chat-input").placeholder = `e.g. ${examples[0]}`;
  const notice = $("#model-notice");
  if (page.modelNotice) {
    // The kernel's notice gives generic examples ("the kitchen light"): use this world's instead.
    const here = `(for example “${examples.slice(0, 3).join("”, “")}”)`;
    const generic = /\("[^)]*\)/;
    setMarkedText(notice, generic.test(page.modelNotice) ? page.modelNotice.replace(generic, here) : `${page.modelNotice} ${here}`);
  }
}

function start() {
  page.running = true;
  $("#login-needed").hidden = true;
  $("#app").hidden = false;
  $("#sign-out").hidden = false;
  followUpdates();
  pollForever("/processes", renderRunning);
  pollForever("/processes?all=true", timelineProcesses);
  pollForever("/confirmations", renderConfirmations);
  detectTimers();
  pollForever("/places", (body) => { renderPlaces(body); listPlaces(body); });
  pollForever("/sightings", renderSightings);
  pollForever("/devices", (devices) => { noteOrigins(devices); renderDevices(devices); suggest(devices); });
  pollForever("/estop", renderEmergencyStop);
}

async function main() {
  $("#chat-form").addEventListener("submit", sendChat);
  $("#running").addEventListener("click", stopProcess);
  $("#chat-log").addEventListener("click", showChatDetails);
  $("#sign-out").addEventListener("click", () => signOut("Signed out."));
  wireEmergencyStop();
  wireMap();
  $("#timeline").addEventListener("click", answerConfirmation);
  $("#timers").addEventListener("click", cancelTimer);
  $("#places").addEventListener("click", placeClicked);
  $("#places").addEventListener("submit", placeRenamed);
  // A new login link pasted into this tab changes only the fragment, which does not reload the
  // page: start over so the new code is used.
  window.addEventListener("hashchange", () => {
    if (location.hash.includes("login=")) location.reload();
  });
  showHealth();
  const code = takeLoginCode();
  if (code) await login(code);
  if (page.token) start();
  else signOut($("#login-error").textContent);
}

main();
