"""The ``reachy`` backends: one class, talking to a real daemon or to a simulated one it starts.

- ``real``: the SDK against the daemon of a Reachy Mini Lite (on this computer's USB) or
  Wireless (on the network), at ``host``:``daemon_port``.
- ``sim``: :class:`~rosaos_reachy.daemon.SimDaemon` starts the SDK's own daemon in simulation
  on a free loopback port, and the same SDK client talks to it. The robot then moves to the
  instance's initial ``sim`` state. There is no media in simulation: speech goes to this
  computer's speaker or a WAV file, and the camera is simulated.

Motion goes through :class:`~rosaos_reachy.motion.MotionController` (one at a time, the
latest wins); speech through :class:`~rosaos_reachy.speech.Speaker`; the robot's own motion
between them (breathing, listening, swaying as it speaks, facing people) through
:class:`~rosaos_reachy.companion.Companion`.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from dataclasses import replace
from pathlib import Path

from rosaos.drivers import DeviceBackend, DeviceContext, DeviceError
from rosaos_reachy.camera import Image, SimCamera, focal_px, grab, pixel_to_angles, save_jpeg
from rosaos_reachy.companion import Companion
from rosaos_reachy.daemon import SimDaemon
from rosaos_reachy.emotions import MoveLibrary, MovesKind, UnknownMove
from rosaos_reachy.faces import FaceDetector, FaceMemory
from rosaos_reachy.motion import MotionController, goto_duration, head_toward
from rosaos_reachy.robot import (
    ANTENNAS_REST,
    NEUTRAL_POSTURE,
    SLEEP_POSTURE,
    HeadPose,
    Posture,
    RobotLink,
)
from rosaos_reachy.settings import ReachySettings, SimSettings
from rosaos_reachy.speech import Speaker
from rosaos_reachy.state import HeadState, MotionReport, PictureReport, ReachyState
from rosaos_reachy.tts import build_engines
from rosaos_reachy.vision import VisionModel

LOOK_YAW, LOOK_PITCH = 30.0, 20.0
"""How far "look left/right/up/down" turns, in degrees."""
MAX_HEAD_YAW, MAX_HEAD_PITCH, MAX_HEAD_ROLL = 60.0, 35.0, 35.0
"""Head limits relative to the body, inside the SDK kinematics' (65° yaw relative to the body)."""
MAX_BODY_YAW = 160.0


class ReachyBackend(DeviceBackend):
    """One Reachy Mini, real or simulated."""

    def __init__(self, ctx: DeviceContext, settings: ReachySettings, sim: SimSettings | None) -> None:
        self.ctx = ctx
        self.settings = settings
        self.sim = sim
        self.simulated = sim is not None
        self.folder = ctx.data_dir / "drivers" / "reachy"
        self.daemon: SimDaemon | None = None
        self.robot = RobotLink(
            settings.host, settings.daemon_port, media=settings.media, timeout=settings.connect_timeout
        )
        self.motion = MotionController(self.robot)
        self.speaker = Speaker(
            build_engines(settings), self.folder / "speech", ctx.data_dir, self.robot, settings.audio_output
        )
        self.moves = MoveLibrary(settings.emotions_dataset, settings.dances_dataset)
        self.face_memory = FaceMemory(self.folder / "faces")
        self.vision = VisionModel(settings)
        self.detector: FaceDetector | None = None
        self.sim_camera: SimCamera | None = None
        self.awake = True
        self.companion = Companion(
            lambda: self.robot,
            self.motion,
            self.speaker,
            lambda: self.awake,
            self._companion_frame,
            lambda: self.detector,
            self.focal_length,
            enabled=settings.companion,
            follow_face=settings.follow_face,
        )
        self.motion.before_foreground = self.companion.yield_now

    # --- lifecycle ----------------------------------------------------------------------------

    async def start(self) -> None:
        """Start the simulated daemon (sim), connect the SDK, and take up the initial state."""
        if self.sim is not None:
            self.daemon = await SimDaemon.start(
                self.sim.physics, self.folder / "sim" / self.ctx.instance, self.sim.start_timeout
            )
            self.robot = RobotLink(
                "127.0.0.1", self.daemon.port, media=False, timeout=self.settings.connect_timeout
            )
            self.motion.robot = self.robot
            self.speaker.robot = self.robot
            self.sim_camera = await asyncio.to_thread(SimCamera.build, self.sim.camera_image)
        await asyncio.to_thread(self.robot.connect)
        self.detector = await asyncio.to_thread(FaceDetector.load)
        await asyncio.to_thread(self.moves.refresh)
        if self.sim is not None:
            await self._take_sim_state(self.sim)
        else:
            measured = self.robot.measured()
            self.awake = self.robot.motors_enabled() and not measured.head.close_to(
                SLEEP_POSTURE.head, 10.0, 10.0
            )
        self.companion.start()

    async def _take_sim_state(self, sim: SimSettings) -> None:
        self.speaker.last_spoken = sim.last_spoken
        self.awake = sim.awake
        if not sim.awake:  # the daemon starts at the sleep pose (--no-wake-up-on-start)
            self.motion.commanded = SLEEP_POSTURE
            await self.motion.settle()
            return
        target = Posture(HeadPose(**sim.head), sim.antennas or ANTENNAS_REST, sim.body_yaw)
        await asyncio.to_thread(self.robot.set_motors, True)
        await self.motion.goto(target, 1.0, "start")

    async def close(self) -> None:
        """Stop motion and speech, disconnect, and stop the simulated daemon (sim)."""
        await self.companion.close()
        with contextlib.suppress(Exception):
            await self.speaker.stop()
        if self.robot.mini is not None:
            await self.motion.close()
            with contextlib.suppress(Exception):
                await asyncio.to_thread(self.robot.close)
        if self.daemon is not None:
            await self.daemon.stop()
            self.daemon = None

    async def safe_stop(self) -> None:
        """Emergency stop: stop moving where it is and stop talking. It stays awake, holding its pose;
        the companion keeps still until a motion tool or ``wake_up`` is called."""
        await self.companion.stop()
        await self.motion.stop()
        await self.speaker.stop()

    # --- state --------------------------------------------------------------------------------

    @property
    def mode(self) -> str:
        if self.daemon is None:
            problem = self.robot.media_problem
            return f"real (no media: {problem})" if problem else "real"
        if self.daemon.mode == "mujoco":
            return "sim: MuJoCo"
        reason = f" ({self.daemon.fallback_reason})" if self.daemon.fallback_reason else ""
        return f"sim: mockup{reason}"

    def state(self) -> ReachyState:
        """The device state; reads the daemon's stream in memory (no round trip)."""
        posture = self.motion.view().posture
        return ReachyState(
            head=HeadState(**posture.head.rounded()),
            antennas=[_r(a) for a in posture.antennas],
            body_yaw=_r(posture.body_yaw),
            awake=self.awake,
            last_spoken=self.speaker.last_spoken,
            speaking=self.speaker.speaking,
            speaking_until=round(self.speaker.speaking_until, 3) if self.speaker.speaking else None,
            moving=self.motion.current,
            mode=self.mode,
            camera="robot"
            if self.robot.has_camera
            else ("simulated" if self.sim_camera is not None else "none"),
            emotions=self.moves.source("emotions"),
            companion=self.companion.mode,
            follow_face=self.companion.follow_face,
        )

    def report(self, message: str) -> MotionReport:
        state = self.state()
        return MotionReport(
            message=message,
            head=state.head,
            antennas=state.antennas,
            body_yaw=state.body_yaw,
            awake=state.awake,
            moving=state.moving,
        )

    def _posture(self) -> Posture:
        return self.motion.commanded or self.robot.measured()

    # --- motion -------------------------------------------------------------------------------

    async def _ensure_awake(self) -> str:
        self.companion.resume()  # an owner moves the robot: after an emergency stop, it may again
        if self.awake:
            return ""
        await self.wake_up()
        return "woke up first; "

    async def look(self, yaw: float, pitch: float, roll: float, what: str) -> MotionReport:
        """Turn the head to ``yaw`` (relative to the body), ``pitch``, ``roll``; wait until there."""
        woke = await self._ensure_awake()
        start = self._posture()
        target = head_toward(start, yaw, pitch, roll)
        await self.motion.goto(target, goto_duration(start, target), f"look {what}", body=False)
        return self.report(f"{woke}looking {what}")

    async def look_at_point(self, x: float, y: float, z: float) -> MotionReport:
        """Look at a point in metres (x forward, y left, z up from the head's neutral centre)."""
        start = self._posture()
        yaw = math.degrees(math.atan2(y, x)) - start.body_yaw
        pitch = -math.degrees(math.atan2(z, math.hypot(x, y)))
        if abs(yaw) > MAX_HEAD_YAW or abs(pitch) > MAX_HEAD_PITCH:
            raise DeviceError(
                f"the point ({x}, {y}, {z}) m is {yaw:+.0f}° to the side and {-pitch:+.0f}° up from where the "
                f"body faces; the head reaches ±{MAX_HEAD_YAW:.0f}° and ±{MAX_HEAD_PITCH:.0f}°: rotate_body first"
            )
        return await self.look(yaw, pitch, 0.0, f"at the point ({x}, {y}, {z}) m")

    async def rotate_body(self, degrees: float) -> MotionReport:
        """Turn the body to ``degrees`` from facing forward; the head turns along with it."""
        woke = await self._ensure_awake()
        start = self._posture()
        turn = degrees - start.body_yaw
        target = replace(start.with_head(yaw=start.head.yaw + turn), body_yaw=degrees)
        await self.motion.goto(target, goto_duration(start, target, maximum=3.0), "rotate body")
        return self.report(f"{woke}body turned to {degrees:+.0f}°")

    async def move_antennas(self, left: float, right: float) -> MotionReport:
        woke = await self._ensure_awake()
        start = self._posture()
        target = Posture(start.head, (left, right), start.body_yaw)
        await self.motion.goto(
            target, goto_duration(start, target, minimum=0.3, maximum=1.0), "antennas", body=False
        )
        return self.report(f"{woke}antennas at left {left:+.0f}°, right {right:+.0f}°")

    async def play(self, kind: MovesKind, name: str, wait: bool) -> MotionReport:
        """Play an emotion or dance; returns when it starts (or ends, with ``wait``)."""
        try:
            choice = self.moves.resolve(kind, name)
        except UnknownMove as error:
            raise DeviceError(str(error)) from None
        woke = await self._ensure_awake()
        move, end = choice.move(self._posture())
        if choice.sound is not None and self.robot.has_speaker:
            await asyncio.to_thread(self.robot.play_sound, str(choice.sound))
        label = f"{kind[:-1]} {choice.name}"
        seconds = await self.motion.play(move, end, label, wait=wait)
        verb = "played" if wait else "playing"
        return self.report(f"{woke}{verb} {label} ({seconds:.1f} s, {choice.source})")

    async def stop_motion(self) -> MotionReport:
        moving = self.motion.current
        stopped = await self.motion.stop()
        return self.report(f"stopped {moving}" if stopped and moving else "nothing was moving")

    async def wake_up(self) -> MotionReport:
        self.companion.resume()
        await self.motion.run("wake up", self.robot.wake_up, NEUTRAL_POSTURE)
        self.awake = True
        return self.report("awake")

    async def sleep(self) -> MotionReport:
        await self.motion.run("go to sleep", self._sleep_blocking, SLEEP_POSTURE)
        self.awake = False
        return self.report("asleep")

    def _sleep_blocking(self) -> None:
        # The SDK's own sequence (goto_sleep), without its sound and trailing 2 s pause:
        # back to the rest pose if far from it, then fold down.
        measured = self.robot.measured()
        if not measured.head.close_to(NEUTRAL_POSTURE.head, 15.0, 15.0):
            self.robot.goto(NEUTRAL_POSTURE, 1.0)
        self.robot.goto(SLEEP_POSTURE, 2.0)
        if self.daemon is None:
            self.robot.set_motors(False)  # rest limp, as the daemon's own sleep does on hardware

    # --- vision -------------------------------------------------------------------------------

    async def take_picture(self) -> tuple[PictureReport, Image]:
        """Capture, save a JPEG in the images directory, and return the report and the image."""
        posture = self.motion.view().posture
        image, simulated = await asyncio.to_thread(grab, self.robot, self.sim_camera, posture)
        path = await asyncio.to_thread(save_jpeg, image, self.ctx.images_dir, self.ctx.instance)
        note = (
            "simulated camera: a generated view of the sim scene, not a real photo"
            if simulated
            else "from the robot's camera"
        )
        height, width = image.shape[:2]
        report = PictureReport(path=path.name, simulated=simulated, width=width, height=height, note=note)
        return report, image

    def focal_length(self, width: int) -> float:
        """Focal length in pixels of the camera that took a ``width``-pixel picture."""
        camera = self.robot.sdk.media.camera if self.robot.has_camera else None
        matrix = getattr(camera, "K", None)
        if matrix is not None:
            return float(matrix[0][0]) * width / float(getattr(camera, "resolution", (width,))[0])
        if self.sim_camera is not None:
            return self.sim_camera.fx
        return focal_px(width, 70.0)

    async def look_toward_pixel(self, u: float, v: float, width: int, height: int, what: str) -> MotionReport:
        """Turn the head so pixel (u, v) of the last picture comes to the centre."""
        d_yaw, d_pitch = pixel_to_angles(u, v, width, height, self.focal_length(width))
        start = self._posture()
        yaw = _clamp(start.head.yaw - start.body_yaw + d_yaw, MAX_HEAD_YAW)
        pitch = _clamp(start.head.pitch + d_pitch, MAX_HEAD_PITCH)
        return await self.look(yaw, pitch, 0.0, what)

    async def _companion_frame(self, posture: Posture) -> Image | None:
        """A frame for ``follow_face``: the robot's camera, else the simulated one, else None."""
        if self.robot.has_camera:
            return await asyncio.to_thread(self.robot.frame)
        return self.sim_camera.frame(posture) if self.sim_camera is not None else None

    @property
    def images_dir(self) -> Path:
        return self.ctx.images_dir


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


def _r(value: float) -> float:
    rounded = round(value, 1)
    return 0.0 if rounded == 0 else rounded
