"""``speak``: synthesize with the first engine that works, then start playback and return.

Playback goes to the robot's speaker when the SDK has media, else to this computer's audio
device, else nowhere but the WAV file (always written, under ``<data>/drivers/reachy/speech``).
:meth:`Speaker.say` returns as soon as playback has started, with the duration, so a process is
never blocked for the length of a sentence; ``speaking_until`` tells the voice front end when to
listen again (it ignores the robot's own voice until then).

A sentence can be cut off: :meth:`Speaker.stop` (the ``stop_speaking`` tool, the voice front
end when the user talks over the robot, the emergency stop) ends the one being played and drops
those waiting their turn; ``say(..., interrupt=True)`` does the same, then says its own.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import logging
import time
import wave
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel

from rosaos.drivers import DeviceError
from rosaos_reachy.robot import RobotLink
from rosaos_reachy.settings import AudioOutput
from rosaos_reachy.tts import TtsEngine, TtsError, wav_duration

log = logging.getLogger(__name__)

KEEP_FILES = 20
"""Speech files kept on disk; older ones are removed."""
MAX_QUEUE_WAIT_S = 30.0
"""A sentence waits at most this long for the one being spoken to end."""
Output = Literal["robot", "host", "file"]


class SpeechReport(BaseModel):
    """What ``speak`` returns."""

    spoken: str
    engine: str
    seconds: float
    """How long the sentence lasts; playback goes on after the tool returns."""
    output: Output
    file: str
    """The WAV file, relative to the rosaOS data directory."""
    speaking_until: float
    """Wall-clock time (epoch seconds) when the robot will have finished speaking."""
    skipped: list[str] = []
    """Engines tried before, and why each was not used."""
    interrupted: bool = False
    """True when the sentence was cut off before it was played (a stop came while it waited)."""
    cut_off: str | None = None
    """With ``interrupt``: the sentence this one cut off, if one was being spoken."""


class StopReport(BaseModel):
    """What ``stop_speaking`` returns."""

    stopped: bool
    """True if the robot was speaking (or had sentences waiting) and now is silent."""
    cut_off: str | None = None
    """The sentence that was cut off."""


@dataclass
class HostAudio:
    """This computer's audio output, through sounddevice (PortAudio)."""

    module: Any

    @classmethod
    def find(cls) -> HostAudio | None:
        """The default output device, or None when there is none (no PortAudio, no sound card)."""
        try:
            import sounddevice

            sounddevice.query_devices(kind="output")
        except Exception:  # OSError without PortAudio, PortAudioError/ValueError without a device
            return None
        return cls(sounddevice)

    def play(self, data: bytes) -> None:
        import numpy as np

        with wave.open(io.BytesIO(data)) as wav:
            frames = wav.readframes(wav.getnframes())
            samples = np.frombuffer(frames, dtype=np.int16).reshape(-1, wav.getnchannels())
            self.module.play(samples, wav.getframerate())  # returns at once; PortAudio plays it

    def stop(self) -> None:
        self.module.stop()


class Speaker:
    """Turns text into speech on the best output there is; one sentence at a time."""

    def __init__(
        self,
        engines: list[TtsEngine],
        folder: Path,
        data_dir: Path,
        robot: RobotLink | None,
        output: AudioOutput,
    ) -> None:
        self.engines = engines
        self.folder = folder
        self.data_dir = data_dir
        self.robot = robot
        self.wanted = output
        self.last_spoken = ""
        self.speaking_until = 0.0
        self._host: HostAudio | None = None
        self._host_checked = False
        self._lock = asyncio.Lock()
        self._count = 0
        self._generation = 0
        """Bumped by every stop: a sentence queued before it is not said."""
        self._stopped = asyncio.Event()
        self._waiting = 0

    def output(self) -> Output:
        """Where speech plays now (see the module docstring)."""
        robot = self.robot is not None and self.robot.has_speaker
        if self.wanted == "robot" and not robot:
            raise DeviceError(
                "audio_output = 'robot' but the robot has no speaker here (no media); use 'auto'"
            )
        if self.wanted in ("auto", "robot") and robot:
            return "robot"
        if self.wanted in ("auto", "host"):
            if not self._host_checked:  # PortAudio and the sound card do not come and go
                self._host, self._host_checked = HostAudio.find(), True
            if self._host is not None:
                return "host"
            if self.wanted == "host":
                raise DeviceError("audio_output = 'host' but this computer has no audio output; use 'auto'")
        return "file"

    @property
    def speaking(self) -> bool:
        return time.time() < self.speaking_until

    async def say(self, text: str, interrupt: bool = False) -> SpeechReport:
        """Synthesize ``text``, start playing it, and return at once with its duration.

        Two processes may answer at once: a sentence waits for the one being spoken to end
        rather than cutting it off, unless ``interrupt`` (then it cuts off the one being
        spoken, and drops those waiting). With no audio output there is nothing to hear, so it
        does not wait; ``speaking_until`` still adds up.
        """
        cut_off = (await self.stop()).cut_off if interrupt else None
        generation = self._generation
        self._waiting += 1
        try:
            async with self._lock:
                data, engine, skipped = await self._synthesize(text)
                seconds = wav_duration(data)
                path = await asyncio.to_thread(self._write, data)
                output = self.output()
                if output != "file" and self.speaking and generation == self._generation:
                    await self._wait_turn(generation)
                report = SpeechReport(
                    spoken=text,
                    engine=engine,
                    seconds=round(seconds, 2),
                    output=output,
                    file=str(path.relative_to(self.data_dir)),
                    speaking_until=round(self.speaking_until, 3),
                    skipped=skipped,
                    cut_off=cut_off,
                )
                if generation != self._generation:  # stopped while it waited or was synthesized
                    return report.model_copy(update={"interrupted": True})
                starts = max(time.time(), self.speaking_until)
                if output == "robot":
                    assert self.robot is not None
                    await asyncio.to_thread(self.robot.play_sound, str(path))
                elif output == "host":
                    assert self._host is not None
                    await asyncio.to_thread(self._host.play, data)
                self.last_spoken = text
                self.speaking_until = starts + seconds
                return report.model_copy(update={"speaking_until": round(self.speaking_until, 3)})
        finally:
            self._waiting -= 1

    async def _wait_turn(self, generation: int) -> None:
        """Wait for the sentence being spoken to end, or for a stop, whichever comes first."""
        self._stopped.clear()
        wait = min(MAX_QUEUE_WAIT_S, self.speaking_until - time.time())
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._stopped.wait(), max(0.0, wait))

    async def stop(self) -> StopReport:
        """Cut off the sentence being played, if any, and drop the sentences waiting their turn."""
        speaking, waiting = self.speaking, self._waiting > 0
        self._generation += 1
        self._stopped.set()
        if not speaking:
            return StopReport(stopped=waiting)
        self.speaking_until = time.time()
        with contextlib.suppress(Exception):
            if self.robot is not None and self.robot.has_speaker:
                await asyncio.to_thread(self.robot.stop_sound)
            if self._host is not None:
                self._host.stop()
        return StopReport(stopped=True, cut_off=self.last_spoken)

    async def _synthesize(self, text: str) -> tuple[bytes, str, list[str]]:
        skipped: list[str] = []
        for engine in self.engines:
            reason = engine.unavailable()
            if reason is not None:
                skipped.append(f"{engine.name}: {reason}")
                continue
            try:
                return await engine.synthesize(text), engine.name, skipped
            except (TtsError, OSError, TimeoutError) as error:
                log.warning("reachy tts %s failed: %s", engine.name, error)
                skipped.append(f"{engine.name}: {error}")
            except Exception as error:  # httpx transport errors and the like: try the next engine
                log.warning("reachy tts %s failed: %s: %s", engine.name, type(error).__name__, error)
                skipped.append(f"{engine.name}: {type(error).__name__}: {error}")
        raise DeviceError("no text-to-speech engine worked: " + "; ".join(skipped))

    def _write(self, data: bytes) -> Path:
        self.folder.mkdir(parents=True, exist_ok=True)
        self._count += 1
        path = self.folder / f"{time.strftime('%Y%m%d-%H%M%S')}-{self._count:04d}.wav"
        path.write_bytes(data)
        for old in sorted(self.folder.glob("*.wav"))[:-KEEP_FILES]:
            with contextlib.suppress(OSError):
                old.unlink()
        return path
