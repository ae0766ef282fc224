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
  renderUntold(state);
  controlsLatched(state);
}

// Hosts the kernel could not tell (a remote robot whose link is down): the latch, or its reset, has
// not reached them. The kernel keeps trying every 2 s; the person should know in the meantime.
function renderUntold(state) {
  const untold = $("#estop-untold");
  const hosts = (state.untold_hosts || []).join(", ");
  untold.hidden = !hosts;
  untold.textContent = !hosts
    ? ""
    : state.latched
      ? `Not told of the emergency stop: ${hosts}. Their hosts did not answer, so they may still act ` +
        "on a direct call; check them and their link. rosaOS keeps trying."
      : `Not told of the reset: ${hosts}. Their hosts still refuse every tool that acts until ` +
        "they hear it; rosaOS keeps trying.";
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
