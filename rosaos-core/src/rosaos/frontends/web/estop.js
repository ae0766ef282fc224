// The emergency-stop control: one button that latches the stop, and a banner with a reset while latched.
// The latch survives a kernel restart, so the first GET /estop after the page loads may already show it.
import { controlsLatched } from "./controls.js";
import { $, api } from "./session.js";

export function renderEmergencyStop(state) {
  const banner = $("#estop-banner");
  const time = $("#estop-time");
  $("#estop").hidden = state.latched;
  banner.hidden = !state.latched;
  $("#estop-reason").textContent = state.latched ? state.reason : "";
  time.dateTime = state.latched && state.time ? state.time : "";
  time.textContent = state.latched && state.time ? new Date(state.time).toLocaleString() : "";
  controlsLatched(state);
}

async function post(path, json) {
  const response = await api(path, { method: "POST", json });
  if (response.ok) renderEmergencyStop(path.endsWith("/reset") ? { latched: false } : await response.json());
}

export function wireEmergencyStop() {
  $("#estop").addEventListener("click", () => post("/estop", { reason: "stop button on the web page" }));
  $("#estop-reset").addEventListener("click", () => {
    if (window.confirm("Is it safe for the robots to move again?")) post("/estop/reset");
  });
}
