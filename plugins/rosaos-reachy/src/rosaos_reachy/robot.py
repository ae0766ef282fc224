"""The Reachy Mini SDK client, wrapped for the driver: poses in degrees and millimetres.

:class:`RobotLink` is the only module that talks to ``reachy_mini``'s ``ReachyMini`` client. Its
methods block (the SDK is synchronous): callers run them with ``asyncio.to_thread``. Reading the
measured pose is the exception: the SDK keeps the daemon's 50 Hz stream in memory.

Conventions, used everywhere in the driver:

- head pose ``x, y, z`` in mm and ``roll, pitch, yaw`` in degrees, from the SDK's ``xyz`` Euler
  angles: positive yaw turns left, positive pitch tilts the head down, positive roll tilts it
  to its right;
- antennas ``(left, right)`` in degrees, mirrored so that equal values are a symmetric pose
  (the SDK takes ``[right, left]`` joint angles in radians, with the right one negated);
- ``body_yaw`` in degrees, positive to the left.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from reachy_mini import ReachyMini
from reachy_mini.io.protocol import GotoTaskRequest, SetFullTargetCmd, SetSpeechOffsetsCmd, StopMoveCmd
from reachy_mini.motion.move import Move
from reachy_mini.reachy_mini import (
    INIT_ANTENNAS_JOINT_POSITIONS,
    SLEEP_ANTENNAS_JOINT_POSITIONS,
    SLEEP_HEAD_POSE,
)
from reachy_mini.utils import create_head_pose
from reachy_mini.utils.interpolation import InterpolationTechnique
from reachy_mini.utils.rotation import Rotation

from rosaos.drivers import DeviceError

log = logging.getLogger(__name__)

LOCAL_HOSTS = {"localhost", "127.0.0.1", "::1"}
STREAM_HZ = 50.0
DAEMON_OVERRUN = "time value is out of range"
"""The daemon's error when its goto loop read the clock past the move's end (see :meth:`RobotLink.goto`)."""
GOTO_ATTEMPTS = 3


@dataclass(frozen=True)
class HeadPose:
    """A head pose relative to the robot's base: mm and degrees (see the module docstring)."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0

    def matrix(self) -> np.ndarray[Any, Any]:
        """The 4x4 pose matrix the SDK takes."""
        return create_head_pose(
            self.x, self.y, self.z, self.roll, self.pitch, self.yaw, mm=True, degrees=True
        )

    @classmethod
    def from_matrix(cls, matrix: Any) -> HeadPose:
        """Decompose an SDK 4x4 pose matrix (metres, rotation) into mm and degrees."""
        m = np.asarray(matrix, dtype=float)
        roll, pitch, yaw = Rotation.from_matrix(m[:3, :3]).as_euler("xyz", degrees=True)
        x, y, z = (m[:3, 3] * 1000.0).tolist()
        return cls(x, y, z, float(roll), float(pitch), float(yaw))

    def close_to(self, other: HeadPose, degrees: float, mm: float) -> bool:
        """Whether ``other`` is within ``degrees`` on every angle and ``mm`` on every axis."""
        return all(abs(getattr(self, k) - getattr(other, k)) <= mm for k in ("x", "y", "z")) and all(
            abs(_angle_diff(getattr(self, k), getattr(other, k))) <= degrees for k in ("roll", "pitch", "yaw")
        )

    def rounded(self) -> dict[str, float]:
        """The pose as ``get_state`` shows it: one decimal, no negative zero."""
        return {k: _round(getattr(self, k)) for k in ("x", "y", "z", "roll", "pitch", "yaw")}


@dataclass(frozen=True)
class Posture:
    """Where the head, antennas and body are (measured) or are told to be (commanded)."""

    head: HeadPose
    antennas: tuple[float, float]
    body_yaw: float

    def with_head(self, **changes: float) -> Posture:
        return replace(self, head=replace(self.head, **changes))


def antennas_to_sdk(left: float, right: float) -> list[float]:
    """``(left, right)`` mirrored degrees → the SDK's ``[right, left]`` joint radians."""
    return [-math.radians(right), math.radians(left)]


def antennas_from_sdk(joints: Any) -> tuple[float, float]:
    """The SDK's ``[right, left]`` joint radians → ``(left, right)`` mirrored degrees."""
    right, left = float(joints[0]), float(joints[1])
    return math.degrees(left), -math.degrees(right)


ANTENNAS_REST = antennas_from_sdk(INIT_ANTENNAS_JOINT_POSITIONS)
"""The SDK's awake rest pose: both antennas about 10° off vertical (it keeps them from shaking)."""
SLEEP_POSTURE = Posture(
    HeadPose.from_matrix(SLEEP_HEAD_POSE), antennas_from_sdk(SLEEP_ANTENNAS_JOINT_POSITIONS), 0.0
)
NEUTRAL_POSTURE = Posture(HeadPose(), ANTENNAS_REST, 0.0)


class RobotLink:
    """One connection to a Reachy Mini daemon through the SDK. Every method but reads blocks."""

    def __init__(self, host: str, port: int, *, media: bool, timeout: float) -> None:
        self.host = host
        self.port = port
        self.media_wanted = media
        self.timeout = timeout
        self.mini: ReachyMini | None = None
        self.media_problem: str | None = None
        """Why the robot's camera and speaker are not used, when media was wanted but failed."""
        self._sending = threading.Lock()
        """Held to send a goto or a stop, so a goto never goes out after a stop it should obey."""

    @property
    def where(self) -> str:
        return f"{self.host}:{self.port}"

    def connect(self) -> None:
        """Connect the SDK client; raise :class:`DeviceError` saying how to fix it."""
        try:
            try:
                self.mini = self._client("default" if self.media_wanted else "no_media")
            except (ConnectionError, TimeoutError, OSError):
                raise
            except Exception as error:  # GStreamer/WebRTC set-up failed: move and speak without media
                log.warning("reachy media unavailable (%s); going on without camera and speaker", error)
                self.media_problem = f"{type(error).__name__}: {error}"
                self.mini = self._client("no_media")
        except (ConnectionError, TimeoutError, OSError) as error:
            raise DeviceError(
                f"cannot reach the Reachy Mini daemon at {self.where}: {error}. Is the robot on? "
                "A Lite needs `reachy-mini-daemon` running on the computer it is plugged into "
                "(host = 'localhost'); a Wireless must be on this network (host = its name or IP)."
            ) from None

    def _client(self, media_backend: str) -> ReachyMini:
        return ReachyMini(
            host=self.host,
            port=self.port,
            connection_mode="localhost_only" if self.host in LOCAL_HOSTS else "network",
            media_backend=media_backend,
            automatic_body_yaw=False,  # the driver turns the body only when asked (rotate_body)
            timeout=self.timeout,
            log_level="WARNING",
        )

    @property
    def sdk(self) -> ReachyMini:
        if self.mini is None:
            raise DeviceError("the Reachy Mini is not connected; the device is starting or closed")
        return self.mini

    # --- reading ------------------------------------------------------------------------------

    def measured(self) -> Posture:
        """The pose the daemon last streamed (50 Hz), without a round trip."""
        head_joints, antenna_joints = self.sdk.get_current_joint_positions()
        head = HeadPose.from_matrix(self.sdk.get_current_head_pose())
        return Posture(head, antennas_from_sdk(antenna_joints), math.degrees(float(head_joints[0])))

    def motors_enabled(self) -> bool:
        status = self.sdk.client.get_status(wait=False)
        backend = getattr(status, "backend_status", None)
        mode = getattr(backend, "motor_control_mode", None)
        return mode is None or str(getattr(mode, "value", mode)) == "enabled"

    # --- moving -------------------------------------------------------------------------------

    def goto(
        self, target: Posture, duration: float, *, body: bool = True, cancel: threading.Event | None = None
    ) -> None:
        """Move smoothly (minimum jerk) to ``target`` in ``duration`` seconds; returns on arrival
        or when :meth:`stop_move` interrupts it.

        The daemon's playback loop (reachy-mini 1.12) checks ``now - t0 < duration`` and then
        reads the clock again to interpolate; when the daemon is descheduled between the two
        reads (a busy computer), the second read lies past the end and the move fails with
        "time value is out of range [0,1]" before its last targets were sent. The driver then
        goes on from where the head is, with a new goto to the same target, unless ``cancel``
        was set meanwhile: a stopped motion stays stopped (the check and the send hold the lock
        :meth:`stop_move` sends under, so a stop cannot slip in between).
        """
        request = GotoTaskRequest(
            head=target.head.matrix().flatten().tolist(),
            antennas=antennas_to_sdk(*target.antennas),
            duration=duration,
            method=InterpolationTechnique.MIN_JERK,
            body_yaw=math.radians(target.body_yaw) if body else None,
        )
        for attempt in range(1, GOTO_ATTEMPTS + 1):
            with self._sending:
                if cancel is not None and cancel.is_set():
                    return
                task = self.sdk.client.send_task_request(request)
            try:
                self.sdk.client.wait_for_task_completion(task, timeout=duration + 1.0)
                return
            except Exception as error:
                if DAEMON_OVERRUN not in str(error) or attempt == GOTO_ATTEMPTS:
                    raise
                log.info("reachy goto overran its clock in the daemon (%s); going on to the target", error)

    def stream(self, move: Move, cancel: threading.Event) -> bool:
        """Play an SDK :class:`Move` by streaming its targets at 50 Hz; False if cancelled."""
        start = time.monotonic()
        period = 1.0 / STREAM_HZ
        while not cancel.is_set():
            t = time.monotonic() - start
            if t >= move.duration:
                return True
            head, antennas, body_yaw = move.evaluate(min(t, move.duration - 1e-3))
            self.sdk.set_target(
                head=head, antennas=list(antennas) if antennas is not None else None, body_yaw=body_yaw
            )
            cancel.wait(max(0.0, period - (time.monotonic() - start - t)))
        return False

    def set_head_offsets(self, offsets: HeadPose) -> None:
        """Offsets the daemon adds to whatever head target it has, before its inverse kinematics
        (the SDK's speech offsets: the daemon's own composition, so they never replace a target)."""
        o = offsets
        values = [
            o.x / 1000.0,
            o.y / 1000.0,
            o.z / 1000.0,
            *(math.radians(a) for a in (o.roll, o.pitch, o.yaw)),
        ]
        self.sdk.client.send_command(SetSpeechOffsetsCmd(offsets=values))

    def set_antennas(self, left: float, right: float) -> None:
        """Set the antenna targets now (no interpolation: the caller streams them)."""
        self.sdk.client.send_command(SetFullTargetCmd(antennas=antennas_to_sdk(left, right)))

    def stop_move(self) -> None:
        """Interrupt whatever move the daemon is playing (the SDK's ``stop_move`` command)."""
        with self._sending:
            self.sdk.client.send_command(StopMoveCmd())

    def set_motors(self, on: bool) -> None:
        if on:
            self.sdk.enable_motors()
        else:
            self.sdk.disable_motors()

    def wake_up(self) -> None:
        """Motors on, then the SDK's wake-up: to the rest pose, with its little head tilt."""
        self.set_motors(True)
        self.sdk.wake_up()

    # --- media --------------------------------------------------------------------------------

    @property
    def has_camera(self) -> bool:
        return self.mini is not None and self.mini.media.camera is not None

    @property
    def has_speaker(self) -> bool:
        return self.mini is not None and self.mini.media.audio is not None

    def frame(self) -> np.ndarray[Any, Any] | None:
        """A BGR frame from the robot's camera, or None."""
        return self.sdk.media.get_frame() if self.has_camera else None

    def play_sound(self, path: str) -> None:
        """Play a sound file on the robot's speaker (uploaded to the daemon when it is remote)."""
        self.sdk.media.play_sound(path)

    def stop_sound(self) -> None:
        self.sdk.media.stop_playing()

    def close(self) -> None:
        """Disconnect; the daemon keeps running (it is the robot's, or the sim backend stops it)."""
        mini, self.mini = self.mini, None
        if mini is not None:
            try:
                mini.media_manager.close()
            finally:
                mini.client.disconnect()


def _angle_diff(a: float, b: float) -> float:
    return (a - b + 180.0) % 360.0 - 180.0


def _round(value: float) -> float:
    rounded = round(value, 1)
    return 0.0 if rounded == 0 else rounded
