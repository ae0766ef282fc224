"""The companion: what the robot does on its own between the motions processes ask for.

A small state machine, :func:`companion_mode`, says what the robot is doing: ``breathing`` when
idle, ``listening`` while the voice front end listens for a command (``listening`` tool),
``speaking`` while :class:`~rosaos_reachy.speech.Speaker` plays a sentence, ``asleep``, or
``off`` (``companion = false``, or after an emergency stop until a motion tool or ``wake_up``).
:class:`Companion` turns it into motion, at :data:`TICK_HZ`:

- the head's small motions (breathing, the sway while speaking) are *offsets* the daemon
  composes with whatever target the head has, before its inverse kinematics (the SDK's
  speech-offset command, the daemon's own scheduling: the one its audio wobbler uses);
- the antennas (breathing, the wave while listening) are set as targets around the commanded
  antenna pose;
- turning toward the speaker and following a face are ordinary, short gotos through
  :class:`~rosaos_reachy.motion.MotionController`, started only when nothing else moves.

It never competes with a process: while a motion tool runs (and for :data:`RESUME_AFTER_S`
after), the offsets are zero and no target is sent, so the process's target is reached
exactly; a process's motion interrupts a companion goto like any newer motion. The device is
``shared`` (every process holds it), so the companion takes no lease: it yields to motion, not
to ownership. It then fades back in over :data:`FADE_S`, around the pose the process left.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from rosaos_reachy.camera import Image, pixel_to_angles
from rosaos_reachy.faces import FaceDetector
from rosaos_reachy.motion import MotionController, head_toward
from rosaos_reachy.robot import HeadPose, Posture, RobotLink
from rosaos_reachy.speech import Speaker
from rosaos_reachy.state import CompanionMode as Mode

log = logging.getLogger(__name__)

TICK_HZ = 20.0
"""How often the offsets and antenna targets are sent (the daemon interpolates between)."""
RESUME_AFTER_S = 0.8
"""After a process's motion ends, stay still this long (its pose is seen as reached) before resuming."""
FADE_S = 1.0
"""Seconds for the companion's motion to fade in, so it never jerks when it resumes."""
FACE_EVERY_S = 0.7
"""How often ``follow_face`` looks for a face (a Haar cascade on one frame: tens of ms)."""
FACE_DEADBAND_DEG = 5.0
"""A face closer than this to the image centre is faced already: no motion."""
FACE_AGREE_DEG = 4.0
"""Two looks in a row must place the face this close to each other before the head turns: one
frame's detection can be a false face, or the head can still be moving."""
TURN_S = 0.8
MAX_GAZE_YAW, MAX_GAZE_PITCH = 60.0, 30.0


@dataclass(frozen=True)
class Offsets:
    """Head offsets (mm, degrees) the daemon adds to the head's target, and antenna offsets (degrees)."""

    head: HeadPose
    antennas: tuple[float, float]

    def scaled(self, k: float) -> Offsets:
        h = self.head
        return Offsets(
            HeadPose(h.x * k, h.y * k, h.z * k, h.roll * k, h.pitch * k, h.yaw * k),
            (self.antennas[0] * k, self.antennas[1] * k),
        )

    def plus(self, other: Offsets) -> Offsets:
        a, b = self.head, other.head
        return Offsets(
            HeadPose(a.x + b.x, a.y + b.y, a.z + b.z, a.roll + b.roll, a.pitch + b.pitch, a.yaw + b.yaw),
            (self.antennas[0] + other.antennas[0], self.antennas[1] + other.antennas[1]),
        )


STILL = Offsets(HeadPose(), (0.0, 0.0))


def _wave(t: float, period: float, phase: float = 0.0) -> float:
    return math.sin(2.0 * math.pi * t / period + phase)


def pattern(mode: Mode, t: float) -> Offsets:
    """The companion's motion in ``mode`` at time ``t`` (seconds).

    Breathing stays inside ``get_state``'s deadband (1.5°, 3 mm, 3° for antennas), so a pose a
    process set still reads as set; listening and speaking are meant to be seen.
    """
    if mode == "breathing":  # a slow breath: the head rises and nods a little, antennas follow
        breath = _wave(t, 4.5)
        return Offsets(HeadPose(z=2.0 * breath, pitch=-1.2 * breath), (2.0 * breath, 2.0 * breath))
    if mode == "listening":  # antennas wave in turn; the head tilts, curious
        wave = 25.0 * _wave(t, 1.2)
        return Offsets(HeadPose(roll=4.0 * _wave(t, 3.0), pitch=-2.0), (wave, -wave))
    if mode == "speaking":  # a gentle sway, two periods mixed so it does not look mechanical
        roll = 3.0 * _wave(t, 2.8) + 1.0 * _wave(t, 1.1, 1.0)
        yaw = 2.5 * _wave(t, 4.3, 0.5)
        pitch = 1.5 * _wave(t, 1.7, 2.0)
        return Offsets(HeadPose(roll=roll, pitch=pitch, yaw=yaw), (4.0 * _wave(t, 2.8), 4.0 * _wave(t, 2.8)))
    return STILL


def companion_mode(*, enabled: bool, stopped: bool, awake: bool, speaking: bool, listening: bool) -> Mode:
    """The companion state machine: the first that applies of off, asleep, speaking, listening, breathing."""
    if not enabled or stopped:
        return "off"
    if not awake:
        return "asleep"
    if speaking:
        return "speaking"
    if listening:
        return "listening"
    return "breathing"


class Companion:
    """Background motion of one Reachy Mini; see the module docstring."""

    def __init__(
        self,
        robot: Callable[[], RobotLink],
        motion: MotionController,
        speaker: Speaker,
        awake: Callable[[], bool],
        frame: Callable[[Posture], Awaitable[Image | None]],
        detector: Callable[[], FaceDetector | None],
        focal_length: Callable[[int], float],
        *,
        enabled: bool,
        follow_face: bool,
    ) -> None:
        self._robot = robot
        self.motion = motion
        self.speaker = speaker
        self._awake = awake
        self._frame = frame
        self._detector = detector
        self._focal_length = focal_length
        self.enabled = enabled
        self.follow_face = follow_face
        self.stopped = False
        self.listening_until = 0.0
        self._turn_to: float | None = None
        """A direction (head yaw, degrees) to turn to when next idle: where the speaker is."""
        self._task: asyncio.Task[None] | None = None
        self._levels: dict[Mode, float] = {}
        """How much of each mode's pattern is in the motion: modes fade in and out of each other."""
        self._sent: Offsets | None = STILL
        self._next_face = 0.0
        self._face_seen: tuple[float, float] | None = None

    # --- what it is doing ---------------------------------------------------------------------

    @property
    def listening(self) -> bool:
        return time.monotonic() < self.listening_until

    @property
    def mode(self) -> Mode:
        return companion_mode(
            enabled=self.enabled,
            stopped=self.stopped,
            awake=self._awake(),
            speaking=self.speaker.speaking,
            listening=self.listening,
        )

    def listen(self, seconds: float, direction: float | None) -> None:
        """The voice front end listens for ``seconds`` (0: stopped); turn toward ``direction`` if given.

        Ignored after an emergency stop: only an owner's motion tool or ``wake_up`` ends that.
        """
        if self.stopped:
            return
        self.listening_until = time.monotonic() + seconds if seconds > 0 else 0.0
        if seconds > 0 and direction is not None:
            self._turn_to = max(-MAX_GAZE_YAW, min(MAX_GAZE_YAW, direction))

    def resume(self) -> None:
        """An owner acted (a motion tool, ``wake_up``): the companion may move again after a stop."""
        self.stopped = False

    async def stop(self) -> None:
        """Emergency stop: no more companion motion until :meth:`resume`; offsets back to zero now."""
        self.stopped = True
        self.listening_until = 0.0
        self._turn_to = None
        await self.yield_now()

    async def yield_now(self) -> None:
        """Keep still at once: a process's motion is about to start (or the robot stops)."""
        self._levels.clear()
        await self._send(STILL, None)

    # --- the loop -----------------------------------------------------------------------------

    def start(self) -> None:
        if self.enabled and self._task is None:
            self._task = asyncio.create_task(self._run(), name="reachy companion")

    async def close(self) -> None:
        task, self._task = self._task, None
        if task is not None:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        with contextlib.suppress(Exception):
            await self._send(STILL, None)

    async def _run(self) -> None:
        period = 1.0 / TICK_HZ
        started = time.monotonic()
        while True:
            try:
                await self._tick(time.monotonic() - started, period)
            except asyncio.CancelledError:
                raise
            except Exception as error:  # a dropped connection must not end the companion for good
                log.warning("reachy companion: %s", error)
                await asyncio.sleep(1.0)
            await asyncio.sleep(period)

    async def _tick(self, t: float, period: float) -> None:
        mode = self.mode
        if mode in ("off", "asleep") or self.motion.busy:
            await self.yield_now()  # the process's target is reached exactly
            return
        if self.motion.current is not None:  # the companion's own turn is under way
            return
        if time.monotonic() - self.motion.foreground_ended < RESUME_AFTER_S:
            return
        if await self._gaze(mode):
            return
        step = period / FADE_S
        for each in {*self._levels, mode}:
            level = self._levels.get(each, 0.0) + (step if each == mode else -step)
            self._levels[each] = max(0.0, min(1.0, level))
        offsets = STILL
        for each, level in self._levels.items():
            if level > 0.0:
                offsets = offsets.plus(pattern(each, t).scaled(level))
        base = self.motion.commanded or self._robot().measured()
        await self._send(offsets, base)

    async def _send(self, offsets: Offsets, base: Posture | None) -> None:
        """Send head offsets (only when changed) and, with a ``base``, the antenna targets around it."""
        robot = self._robot()
        if robot.mini is None:
            return
        if offsets != self._sent:
            await asyncio.to_thread(robot.set_head_offsets, offsets.head)
            self._sent = offsets
        if base is not None:
            left, right = base.antennas
            await asyncio.to_thread(
                robot.set_antennas, left + offsets.antennas[0], right + offsets.antennas[1]
            )

    # --- turning toward people ----------------------------------------------------------------

    async def _gaze(self, mode: Mode) -> bool:
        """Turn toward the speaker (once, after a wake) or a face in view; True if a turn started."""
        if self._turn_to is not None:
            yaw, self._turn_to = self._turn_to, None
            return await self._turn(yaw, 0.0, "companion: turn to the speaker")
        if (
            not self.follow_face
            or mode not in ("listening", "speaking")
            or time.monotonic() < self._next_face
        ):
            return False
        self._next_face = time.monotonic() + FACE_EVERY_S
        aim = await self._face_direction()
        seen, self._face_seen = self._face_seen, aim
        if aim is None or seen is None or math.hypot(aim[0] - seen[0], aim[1] - seen[1]) > FACE_AGREE_DEG:
            return False
        self._face_seen = None
        self._next_face = time.monotonic() + TURN_S + FACE_EVERY_S  # look again once the head is there
        return await self._turn(*aim, "companion: follow face")

    async def _face_direction(self) -> tuple[float, float] | None:
        """Head (yaw, pitch) relative to the body that faces the largest face in view, or None."""
        detector = self._detector()
        posture = self._robot().measured()
        image = await self._frame(posture)
        if detector is None or image is None:
            return None
        boxes = await asyncio.to_thread(detector.detect, image)
        if not boxes:
            return None
        x, y, w, h = boxes[0]
        height, width = image.shape[:2]
        d_yaw, d_pitch = pixel_to_angles(x + w / 2, y + h / 2, width, height, self._focal_length(width))
        if math.hypot(d_yaw, d_pitch) < FACE_DEADBAND_DEG:
            return None
        # From where the head is (the frame was taken there), not where it was told to be.
        yaw = posture.head.yaw - posture.body_yaw + d_yaw
        pitch = posture.head.pitch + d_pitch
        return (max(-MAX_GAZE_YAW, min(MAX_GAZE_YAW, yaw)), max(-MAX_GAZE_PITCH, min(MAX_GAZE_PITCH, pitch)))

    async def _turn(self, yaw: float, pitch: float, label: str) -> bool:
        start = self.motion.commanded or self._robot().measured()
        target = head_toward(start, yaw, pitch, 0.0)
        if start.head.close_to(target.head, FACE_DEADBAND_DEG / 2, 5.0):
            return False
        await self._send(STILL, None)  # the turn starts from where the head is, offsets off
        return await self.motion.goto_in_background(target, TURN_S, label)
