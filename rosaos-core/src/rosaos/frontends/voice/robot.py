"""The Reachy Mini's side of listening: tell it when it listens; know when it talks.

The voice front end uses the robot the way processes do: through the reachy instance's MCP tools
(``set_listening``, ``speak``, ``stop_speaking``, ``get_state``), found through the kernel's
``GET /devices``. Without a served reachy instance there is nothing to move; that is logged once
and listening goes on.

On the wake phrase, ``set_listening(on=true, direction=...)`` hands the gestures to the driver's
companion: it turns toward the speaker (the microphone array's direction of arrival, when the
audio source gives one) and waves its antennas while it listens, as background motion that never
interrupts a process's; once the command is sent, ``set_listening(on=false)``.

While the robot speaks, its own voice reaches the microphones. :meth:`ReachyLink.muted` says when
to ignore audio: until ``speaking_until`` (epoch seconds) if ``get_state`` gives it, while
``speaking`` is true, or else for an estimate of how long the newest ``last_spoken`` takes to say. When the user talks over the robot
(barge-in, :mod:`rosaos.frontends.voice.bargein`), :meth:`ReachyLink.unmute` listens again at once
and :meth:`ReachyLink.stop_speaking` cuts the sentence off with the driver's ``stop_speaking``.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from typing import TYPE_CHECKING, Any, Protocol

from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

if TYPE_CHECKING:  # imported when a Reachy is found: the MCP client costs the voice process ~45 MiB
    from rosaos.devices.client import DeviceClient

log = logging.getLogger(__name__)

SPEECH_CHARS_PER_SECOND = 14.0
"""Typical TTS speed, for when the driver does not say how long it will speak."""
ECHO_TAIL_SECONDS = 0.4
"""Room reverb and playout buffering after the robot's last word."""
POLL_SECONDS = 0.25
MAX_YAW_DEGREES = 60.0


class RobotLink(Protocol):
    """What the pipeline asks of the robot. :class:`NoRobot` when there is none."""

    async def woke(self, doa: float | None, seconds: float) -> None:
        """Someone woke the robot: it listens for ``seconds``, turned toward ``doa`` (radians, SDK
        convention; None: where it faces)."""
        ...

    async def listened(self) -> None:
        """The command was heard: the robot stops listening."""
        ...

    def muted(self, wall: float) -> bool:
        """The robot is speaking at wall-clock time ``wall``: ignore that audio."""
        ...

    async def say(self, text: str) -> bool:
        """Say ``text`` to the user; True if the robot is saying it."""
        ...

    async def follow(self) -> None:
        """Keep track of whether the robot is speaking, until cancelled."""
        ...

    def unmute(self) -> None:
        """Listen again now: the user is talking over the robot."""
        ...

    async def stop_speaking(self) -> bool:
        """Cut off what the robot is saying; True if it was speaking."""
        ...


class NoRobot:
    """No reachy instance is served: nothing to move, nothing to ignore."""

    async def woke(self, doa: float | None, seconds: float) -> None:
        return None

    async def listened(self) -> None:
        return None

    def muted(self, wall: float) -> bool:
        return False

    async def say(self, text: str) -> bool:
        return False

    async def follow(self) -> None:
        return None

    def unmute(self) -> None:
        return None

    async def stop_speaking(self) -> bool:
        return False


def doa_to_yaw(doa: float) -> float:
    """Head yaw in degrees (positive = left) for a direction of arrival in radians.

    The Reachy SDK gives 0 for left, pi/2 for straight ahead (or behind) and pi for right.
    """
    yaw = 90.0 - math.degrees(doa)
    return max(-MAX_YAW_DEGREES, min(MAX_YAW_DEGREES, round(yaw, 1)))


class ReachyLink:
    """The reachy instance's MCP tools, through a :class:`DeviceClient`."""

    def __init__(self, device: DeviceClient) -> None:
        from rosaos.drivers import DeviceError

        self.device = device
        self._errors: tuple[type[Exception], ...] = (DeviceError,)
        """What a failed tool call raises (imported with the MCP client, only when there is a robot)."""
        self.muted_until = 0.0
        self._last_spoken: str | None = None
        self._failed: set[str] = set()
        self._unmuted_at = 0.0
        """Wall time of the last barge-in, or of its ``stop_speaking``'s answer: a ``get_state``
        asked before it is stale."""
        self._stops_in_flight = 0
        """``stop_speaking`` calls not answered yet: meanwhile ``get_state`` may still show the
        sentence being cut off (a busy machine answered one after the barge-in: CI, 3 workers)."""

    async def woke(self, doa: float | None, seconds: float) -> None:
        args: dict[str, Any] = {"on": True, "seconds": round(max(1.0, min(120.0, seconds)), 1)}
        if doa is not None:
            args["direction"] = doa_to_yaw(doa)
        await self._call("set_listening", args)

    async def listened(self) -> None:
        await self._call("set_listening", {"on": False})

    def muted(self, wall: float) -> bool:
        return wall <= self.muted_until

    async def say(self, text: str) -> bool:
        try:
            report = await self.device.call("speak", {"text": text})
        except self._errors as error:
            log.warning("reachy could not say %r: %s", text, error)
            return False
        # Stop listening at once rather than at the next get_state poll: the voice starts now.
        until = (
            report.get("speaking_until")
            if isinstance(report, dict)
            else getattr(report, "speaking_until", None)
        )
        if isinstance(until, int | float):
            self.muted_until = max(self.muted_until, float(until) + ECHO_TAIL_SECONDS)
        return True

    async def follow(self) -> None:
        while True:
            try:
                # One MCP session for the whole run, shared by every call meanwhile: a barge-in's
                # stop_speaking then costs one request, not a new session's handshake first.
                async with self.device:
                    while True:
                        await self._poll()
                        await asyncio.sleep(POLL_SECONDS)
            except Exception as error:  # the reachy host restarted: open a new session
                log.debug("reachy session ended (%s); opening a new one", error)
                await asyncio.sleep(POLL_SECONDS)

    async def _poll(self) -> None:
        asked = time.time()
        state = await self.device.get_state()
        if asked >= self._unmuted_at and not self._stops_in_flight:  # else: the sentence just cut off
            self.observe(state, time.time())

    def unmute(self) -> None:
        self._unmuted_at = time.time()
        self.muted_until = 0.0

    async def stop_speaking(self) -> bool:
        self._stops_in_flight += 1
        try:
            report = await self.device.call("stop_speaking", {})
        except self._errors as error:
            log.warning("reachy could not stop speaking: %s", error)
            return False
        finally:
            self._stops_in_flight -= 1
            self._unmuted_at = max(self._unmuted_at, time.time())
        stopped = report.get("stopped") if isinstance(report, dict) else getattr(report, "stopped", False)
        return bool(stopped)

    def observe(self, state: dict[str, Any], now: float) -> None:
        """Update :attr:`muted_until` from one ``get_state`` reading taken at ``now``."""
        until = state.get("speaking_until")
        if isinstance(until, int | float):
            self.muted_until = max(self.muted_until, float(until) + ECHO_TAIL_SECONDS)
        elif state.get("speaking") is True:
            self.muted_until = max(self.muted_until, now + POLL_SECONDS + ECHO_TAIL_SECONDS)
        spoken = state.get("last_spoken")
        if isinstance(spoken, str) and spoken != self._last_spoken:
            if self._last_spoken is not None and "speaking_until" not in state and "speaking" not in state:
                estimate = len(spoken) / SPEECH_CHARS_PER_SECOND
                self.muted_until = max(self.muted_until, now + estimate + ECHO_TAIL_SECONDS)
            self._last_spoken = spoken

    async def _call(self, tool: str, args: dict[str, Any]) -> bool:
        try:
            await self.device.call(tool, args)
            return True
        except self._errors as error:
            if tool not in self._failed:  # say it once, not on every wake
                self._failed.add(tool)
                log.warning("reachy %s failed, skipping it: %s", tool, error)
            return False


async def find_reachy(kernel: KernelClient, token: str) -> RobotLink:
    """A link to the served reachy instance, or :class:`NoRobot` (logged once) when none is."""
    try:
        devices = await kernel.request("GET", "/devices")
    except KernelUnavailable as error:
        log.info("no robot gestures: cannot list devices (%s)", error)
        return NoRobot()
    for device in devices or []:
        if device.get("driver") != "reachy":
            continue
        state = device.get("state") or {}
        if not device.get("url") or state.get("implemented") is False:
            log.info("no robot gestures: reachy instance %r is not served", device.get("name"))
            return NoRobot()
        from rosaos.devices.client import DeviceClient

        return ReachyLink(DeviceClient(device["url"], token, timeout=5, name=device.get("name")))
    log.info("no robot gestures: the kernel serves no reachy instance")
    return NoRobot()
