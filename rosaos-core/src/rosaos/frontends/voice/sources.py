"""Audio sources: a WAV file, the host microphone, the Reachy Mini's microphones; and camera frames.

Every source yields :class:`AudioChunk` s of mono float32 audio at :data:`SAMPLE_RATE`, whatever
the device gives, so the rest of the pipeline never resamples. Hardware libraries (sounddevice,
the Reachy Mini SDK) are imported only when their source is opened, and a missing one is a
:class:`VoiceError` that says what to install.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import struct
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

SAMPLE_RATE = 16_000
"""What every engine here wants: Silero VAD, Moonshine, Whisper."""

Samples = NDArray[np.float32]
SOX_HINT = "convert it with: sox INPUT.wav -r 16000 -c 1 -b 16 OUTPUT.wav"


class VoiceError(Exception):
    """The voice front end cannot go on; the message says what to install or change."""


@dataclass(frozen=True)
class AudioChunk:
    """A stretch of mono 16 kHz audio in [-1, 1]."""

    samples: Samples
    start: float
    """Seconds since the stream started (file time for a WAV file)."""
    wall: float
    """Wall-clock time (epoch seconds) of the first sample."""
    doa: float | None = None
    """Direction of arrival in radians, where the hardware gives one (Reachy: 0 left, pi/2 front)."""


class AudioSource(Protocol):
    """Where audio comes from. ``chunks`` ends when the source does (a file) or never (a mic)."""

    name: str
    """Stable identity of the source, part of every idempotency key: ``wav:/abs/path``, ``mic``."""
    live: bool
    """True for microphones: the robot's own voice must be ignored by wall-clock time."""

    def chunks(self, chunk_samples: int) -> AsyncIterator[AudioChunk]:
        """Yield chunks of exactly ``chunk_samples`` (the last one of a file may be shorter)."""
        ...


def _lowpass(rate_in: int, rate_out: int) -> NDArray[np.float64] | None:
    """A windowed-sinc low-pass below the new Nyquist, so downsampling does not alias; None upsampling."""
    if rate_out >= rate_in:
        return None
    cutoff = 0.45 * rate_out / rate_in  # in cycles per input sample
    taps = np.arange(-32, 33)
    kernel = 2 * cutoff * np.sinc(2 * cutoff * taps) * np.hamming(taps.size)
    return np.asarray(kernel / kernel.sum(), dtype=np.float64)


def resample(samples: Samples, rate_in: int, rate_out: int = SAMPLE_RATE) -> Samples:
    """Resample a whole recording: low-pass, then linear interpolation."""
    if rate_in == rate_out or samples.size == 0:
        return samples.astype(np.float32, copy=False)
    kernel = _lowpass(rate_in, rate_out)
    if kernel is not None:
        samples = np.convolve(samples, kernel, mode="same").astype(np.float32)
    positions = np.arange(round(samples.size * rate_out / rate_in)) * (rate_in / rate_out)
    return np.interp(positions, np.arange(samples.size), samples).astype(np.float32)


class StreamResampler:
    """Resamples a live stream block by block without seams: filter history and phase carry over."""

    def __init__(self, rate_in: int, rate_out: int = SAMPLE_RATE) -> None:
        self.step = rate_in / rate_out
        self.same = rate_in == rate_out
        self._kernel = _lowpass(rate_in, rate_out)
        self._history = np.zeros(0 if self._kernel is None else self._kernel.size - 1, np.float32)
        self._buffer = np.zeros(0, np.float32)
        self._position = 0.0
        """Where the next output sample falls, in input samples from ``_buffer[0]``."""

    def push(self, block: Samples) -> Samples:
        if self.same:
            return block.astype(np.float32, copy=False)
        if self._kernel is not None:
            padded = np.concatenate([self._history, block])
            block = np.convolve(padded, self._kernel, mode="valid").astype(np.float32)
            self._history = padded[padded.size - self._history.size :]
        buffer = np.concatenate([self._buffer, block])
        count = max(0, int(np.floor((buffer.size - 1 - self._position) / self.step)) + 1)
        if buffer.size < 2 or count == 0:
            self._buffer = buffer
            return np.zeros(0, np.float32)
        positions = self._position + np.arange(count) * self.step
        out = np.interp(positions, np.arange(buffer.size), buffer).astype(np.float32)
        following = self._position + count * self.step
        consumed = min(int(np.floor(following)), buffer.size - 1)  # keep one sample to interpolate from
        self._buffer = buffer[consumed:]
        self._position = following - consumed
        return out


def to_mono(frames: NDArray[Any]) -> Samples:
    """Average the channels of a (frames, channels) array; a 1-D array is already mono."""
    array = np.asarray(frames, dtype=np.float32)
    return array if array.ndim == 1 else array.mean(axis=1, dtype=np.float32)


def read_wav(path: Path) -> Samples:
    """A WAV file of any rate and channel count (PCM 8/16/24/32-bit or float) as mono 16 kHz float32."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise VoiceError(f"{path}: no such WAV file") from None
    except OSError as error:
        raise VoiceError(f"{path}: cannot read it ({error.strerror})") from None
    try:
        fmt, raw = _riff_chunks(data)
        tag, channels, rate = struct.unpack_from("<HHI", fmt)
        bits = struct.unpack_from("<H", fmt, 14)[0]
        if tag == WAVE_FORMAT_EXTENSIBLE and len(fmt) >= 26:
            tag = struct.unpack_from("<H", fmt, 24)[0]  # the sub-format GUID starts with the real tag
    except (ValueError, struct.error) as error:
        raise VoiceError(f"{path}: not a WAV file ({error}); {SOX_HINT}") from None
    width = bits // 8
    if (tag, width) not in _DECODERS or channels < 1 or rate < 1:
        raise VoiceError(f"{path}: unsupported WAV encoding (format {tag}, {bits}-bit); {SOX_HINT}")
    usable = len(raw) - len(raw) % (width * channels)
    pcm = np.asarray(_DECODERS[(tag, width)](raw[:usable]), dtype=np.float32)
    return resample(to_mono(pcm.reshape(-1, channels)), rate)


WAVE_FORMAT_PCM, WAVE_FORMAT_FLOAT, WAVE_FORMAT_EXTENSIBLE = 1, 3, 0xFFFE


def _riff_chunks(data: bytes) -> tuple[bytes, bytes]:
    """The ``fmt `` and ``data`` chunks of a RIFF/WAVE file (Python 3.11's wave module rejects
    WAVE_FORMAT_EXTENSIBLE, which sox writes for piped output)."""
    if len(data) < 12 or data[:4] != b"RIFF" or data[8:12] != b"WAVE":
        raise ValueError("no RIFF/WAVE header")
    chunks: dict[bytes, bytes] = {}
    offset = 12
    while offset + 8 <= len(data):
        name, size = data[offset : offset + 4], struct.unpack_from("<I", data, offset + 4)[0]
        chunks.setdefault(name, data[offset + 8 : offset + 8 + size])
        offset += 8 + size + size % 2  # chunks are word-aligned
    if b"fmt " not in chunks or b"data" not in chunks:
        raise ValueError("no fmt or data chunk")
    return chunks[b"fmt "], chunks[b"data"]


def _pcm24(raw: bytes) -> Samples:
    bytes3 = np.frombuffer(raw, np.uint8).reshape(-1, 3).astype(np.int32)
    value = bytes3[:, 0] | (bytes3[:, 1] << 8) | (bytes3[:, 2] << 16)
    return (np.where(value >= 1 << 23, value - (1 << 24), value) / float(1 << 23)).astype(np.float32)


_DECODERS: dict[tuple[int, int], Callable[[bytes], NDArray[Any]]] = {
    (WAVE_FORMAT_PCM, 1): lambda raw: (np.frombuffer(raw, np.uint8).astype(np.float32) - 128) / 128,
    (WAVE_FORMAT_PCM, 2): lambda raw: np.frombuffer(raw, "<i2").astype(np.float32) / 32768,
    (WAVE_FORMAT_PCM, 3): _pcm24,
    (WAVE_FORMAT_PCM, 4): lambda raw: (np.frombuffer(raw, "<i4") / float(1 << 31)).astype(np.float32),
    (WAVE_FORMAT_FLOAT, 4): lambda raw: np.frombuffer(raw, "<f4").astype(np.float32),
    (WAVE_FORMAT_FLOAT, 8): lambda raw: np.frombuffer(raw, "<f8").astype(np.float32),
}


class Rechunker:
    """Turns blocks of any size into chunks of exactly ``size`` samples."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._pending = np.zeros(0, np.float32)

    def push(self, samples: Samples) -> list[Samples]:
        self._pending = np.concatenate([self._pending, samples.astype(np.float32, copy=False)])
        count = self._pending.size // self.size
        chunks = [self._pending[i * self.size : (i + 1) * self.size] for i in range(count)]
        self._pending = self._pending[count * self.size :]
        return chunks


class WavSource:
    """A WAV file, for tests and demos. ``paced`` delivers it at real-time speed, like a microphone.

    ``live`` plays the file as if it were a microphone in the room (paced): the robot's own voice
    is then ignored by time, and the user can talk over it (barge-in).
    """

    def __init__(self, path: Path, paced: bool = False, *, live: bool = False) -> None:
        self.path = path.resolve()
        self.name = f"wav:{self.path}"
        self.live = live
        self.paced = paced or live
        self.samples = read_wav(self.path)
        self.started_wall = time.time()
        self.began: float | None = None
        """``time.monotonic()`` when reading began: a paced file's "speaker" started then."""

    async def chunks(self, chunk_samples: int) -> AsyncIterator[AudioChunk]:
        begun = self.began = time.monotonic()
        if self.paced:  # its chunks' wall times are when they are "heard", as a microphone's are
            self.started_wall = time.time()
        for offset in range(0, self.samples.size, chunk_samples):
            piece = self.samples[offset : offset + chunk_samples]
            start = offset / SAMPLE_RATE
            if self.paced:  # a chunk exists only once its last sample has been "spoken"
                await asyncio.sleep(max(0.0, begun + start + piece.size / SAMPLE_RATE - time.monotonic()))
            else:
                await asyncio.sleep(0)  # let transcription and hand-off tasks run between chunks
            yield AudioChunk(piece, start, self.started_wall + start)


class MicSource:
    """The host's default microphone through sounddevice (PortAudio)."""

    live = True
    name = "mic"

    async def chunks(self, chunk_samples: int) -> AsyncIterator[AudioChunk]:
        sounddevice = _import_sounddevice()
        loop = asyncio.get_running_loop()
        queue: asyncio.Queue[Samples] = asyncio.Queue(maxsize=500)

        def deliver(block: Samples) -> None:
            with contextlib.suppress(asyncio.QueueFull):  # the loop is stalled: drop audio, not the stream
                queue.put_nowait(block)

        def on_audio(block: NDArray[np.float32], frames: int, when: Any, status: Any) -> None:
            # PortAudio's thread: hand a copy to the event loop (closed already while stopping: ignore).
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(deliver, to_mono(block).copy())

        stream, rate = _open_input(sounddevice, chunk_samples, on_audio)
        resampler, rechunk = StreamResampler(rate), Rechunker(chunk_samples)
        t0_wall, produced = time.time(), 0
        with stream:
            while True:
                for chunk in rechunk.push(resampler.push(await queue.get())):
                    start = produced / SAMPLE_RATE
                    produced += chunk.size
                    yield AudioChunk(chunk, start, t0_wall + start)


def _import_sounddevice() -> Any:
    try:
        import sounddevice
    except ImportError:
        raise VoiceError("the microphone source needs sounddevice: pip install 'rosaos[voice]'") from None
    except OSError:  # sounddevice loads libportaudio when imported
        raise VoiceError(
            "the microphone source needs the PortAudio library: apt-get install libportaudio2 "
            "(macOS: brew install portaudio)"
        ) from None
    return sounddevice


def _open_input(sounddevice: Any, chunk_samples: int, callback: Callable[..., None]) -> tuple[Any, int]:
    """An input stream at 16 kHz, or at the device's own rate when it refuses 16 kHz."""
    try:
        device = sounddevice.query_devices(kind="input")
    except Exception as error:
        raise VoiceError(f"no microphone found ({error}); plug one in, or use --wav FILE") from None
    for rate in (SAMPLE_RATE, int(device["default_samplerate"])):
        try:
            blocksize = math.ceil(chunk_samples * rate / SAMPLE_RATE)
            stream = sounddevice.InputStream(
                samplerate=rate, channels=1, dtype="float32", blocksize=blocksize, callback=callback
            )
            return stream, rate
        except sounddevice.PortAudioError as error:
            last = error
    raise VoiceError(f"cannot open the microphone {device['name']!r}: {last}")


class ReachyMedia(Protocol):
    """What the voice front end needs from the Reachy Mini's media (the SDK's ``MediaManager``)."""

    def start_recording(self) -> None: ...

    def get_audio_sample(self) -> NDArray[np.float32] | None: ...

    def get_input_audio_samplerate(self) -> int: ...

    def get_DoA(self) -> tuple[float, bool] | None: ...  # the SDK's name

    def get_frame(self) -> NDArray[np.uint8] | None: ...


def open_reachy_media(host: str, port: int = 8000) -> tuple[ReachyMedia, Callable[[], None]]:
    """Connect to the Reachy Mini daemon with media; returns the media and a close function."""
    try:
        from reachy_mini import ReachyMini
    except ImportError as error:
        raise VoiceError(
            f"--source reachy needs the Reachy Mini SDK, which is not importable here ({error}): "
            "pip install reachy-mini==1.12.0 (the rosaos-reachy driver brings it), or use --source mic"
        ) from None
    try:
        local = host in ("localhost", "127.0.0.1", "::1")
        mini = ReachyMini(
            host=host,
            port=port,
            connection_mode="localhost_only" if local else "network",
            media_backend="default",
            log_level="WARNING",
        )
    except Exception as error:
        raise VoiceError(
            f"cannot reach the Reachy Mini daemon at {host}:{port} with media ({type(error).__name__}: {error}); "
            "is the robot on and its daemon running? Set [voice] reachy_host/reachy_port, or use --source mic"
        ) from None
    media = mini.media
    return media, lambda: _close_quietly(media)


def require_media(media: ReachyMedia, part: str, fix: str) -> None:
    """Fail clearly when the daemon serves no ``audio`` or ``camera`` (``--no-media``, the simulator)."""
    if getattr(media, part, True) is None:
        raise VoiceError(
            f"the Reachy Mini daemon serves no {part} (started with --no-media, or a simulator); {fix}"
        )


def _close_quietly(media: Any) -> None:
    with contextlib.suppress(Exception):
        media.close()


class ReachySource:
    """The Reachy Mini's microphone array, with its direction of arrival when the firmware gives one."""

    live = True
    name = "reachy"
    POLL_SECONDS = 0.01

    def __init__(self, media: ReachyMedia, close: Callable[[], None] | None = None) -> None:
        self.media = media
        self._close = close

    async def chunks(self, chunk_samples: int) -> AsyncIterator[AudioChunk]:
        await asyncio.to_thread(self.media.start_recording)
        resampler = StreamResampler(self.media.get_input_audio_samplerate())
        rechunk = Rechunker(chunk_samples)
        t0_wall, produced = time.time(), 0
        try:
            while True:
                block = await asyncio.to_thread(self.media.get_audio_sample)
                if block is None or block.size == 0:
                    await asyncio.sleep(self.POLL_SECONDS)
                    continue
                doa = self.direction()
                for chunk in rechunk.push(resampler.push(to_mono(block))):
                    start = produced / SAMPLE_RATE
                    produced += chunk.size
                    yield AudioChunk(chunk, start, t0_wall + start, doa)
        finally:
            if self._close is not None:
                self._close()

    def direction(self) -> float | None:
        """The latest direction of arrival while speech is detected, else None."""
        try:
            reading = self.media.get_DoA()
        except Exception:  # no ReSpeaker, old firmware, USB busy: just no direction
            return None
        if reading is None or not reading[1]:
            return None
        return float(reading[0])


class FrameSource(Protocol):
    """Camera frames (BGR uint8 arrays) for eye-contact wake."""

    def frames(self) -> AsyncIterator[NDArray[np.uint8]]: ...


class ReachyCamera:
    """Frames from the Reachy Mini's camera, a few per second (enough to see someone looking)."""

    def __init__(self, media: ReachyMedia, fps: float = 5.0) -> None:
        self.media = media
        self.period = 1 / fps

    async def frames(self) -> AsyncIterator[NDArray[np.uint8]]:
        while True:
            frame = await asyncio.to_thread(self.media.get_frame)
            if frame is not None:
                yield frame
            await asyncio.sleep(self.period)
