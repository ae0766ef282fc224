"""Audio sources: any WAV becomes mono 16 kHz, chunks are exact, hardware gaps are explained."""

from __future__ import annotations

import itertools
import struct
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rosaos.frontends.voice.sources import (
    SAMPLE_RATE,
    MicSource,
    ReachySource,
    StreamResampler,
    VoiceError,
    WavSource,
    open_reachy_media,
    read_wav,
    resample,
)
from rosaos.frontends.voice.stt import wav_bytes

from .voice_support import tone


def write_wav(path: Path, frames: np.ndarray, rate: int, fmt: int = 1, extensible: bool = False) -> Path:
    """A WAV file written by hand, so every encoding (including WAVE_FORMAT_EXTENSIBLE) is covered."""
    channels = 1 if frames.ndim == 1 else frames.shape[1]
    data = frames.tobytes()
    width = frames.dtype.itemsize
    tag = 0xFFFE if extensible else fmt
    fmt_chunk = struct.pack(
        "<HHIIHH", tag, channels, rate, rate * channels * width, channels * width, width * 8
    )
    if extensible:
        fmt_chunk += struct.pack("<HHI", 22, width * 8, 0) + struct.pack("<H", fmt) + b"\x00" * 14
    body = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt_chunk)) + fmt_chunk
    body += b"data" + struct.pack("<I", len(data)) + data
    path.write_bytes(b"RIFF" + struct.pack("<I", len(body)) + body)
    return path


def dominant_hz(samples: np.ndarray) -> float:
    spectrum = np.abs(np.fft.rfft(samples))
    return float(np.fft.rfftfreq(samples.size, 1 / SAMPLE_RATE)[spectrum.argmax()])


def test_a_16khz_mono_wav_is_read_as_it_is(tmp_path: Path) -> None:
    original = tone(1.0)
    samples = read_wav(_write(tmp_path, wav_bytes(original)))
    assert samples.dtype == np.float32 and samples.size == SAMPLE_RATE
    assert np.max(np.abs(samples - original)) < 1e-3


def _write(tmp_path: Path, data: bytes) -> Path:
    path = tmp_path / "in.wav"
    path.write_bytes(data)
    return path


def test_a_stereo_22khz_wav_becomes_mono_16khz_with_the_same_pitch(tmp_path: Path) -> None:
    t = np.arange(22050) / 22050
    left = (0.3 * np.sin(2 * np.pi * 440 * t) * 32767).astype("<i2")
    path = write_wav(tmp_path / "s.wav", np.stack([left, left], axis=1), 22050)
    samples = read_wav(path)
    assert samples.size == pytest.approx(SAMPLE_RATE, abs=1)
    assert dominant_hz(samples) == pytest.approx(440, abs=2)


@pytest.mark.parametrize(
    ("dtype", "fmt", "scale"),
    [("<i2", 1, 32767), ("<i4", 1, 2**31 - 1), ("<f4", 3, 1.0), ("u1", 1, None)],
)
def test_pcm_and_float_encodings_are_read(tmp_path: Path, dtype: str, fmt: int, scale: float | None) -> None:
    wave = tone(0.5, level=0.5)
    frames = (wave * 127 + 128).astype(dtype) if scale is None else (wave * scale).astype(dtype)
    samples = read_wav(write_wav(tmp_path / "x.wav", frames, SAMPLE_RATE, fmt))
    assert np.max(np.abs(samples - wave)) < 0.02


def test_wave_format_extensible_as_sox_writes_it_is_read(tmp_path: Path) -> None:
    frames = (tone(0.5) * 32767).astype("<i2")
    samples = read_wav(write_wav(tmp_path / "x.wav", frames, SAMPLE_RATE, 1, extensible=True))
    assert samples.size == frames.size


def test_a_file_that_is_not_a_wav_says_how_to_convert_it(tmp_path: Path) -> None:
    path = tmp_path / "song.mp3"
    path.write_bytes(b"ID3" + b"\x00" * 100)
    with pytest.raises(VoiceError, match=r"sox INPUT\.wav -r 16000 -c 1 -b 16 OUTPUT\.wav"):
        read_wav(path)


def test_a_missing_wav_says_so(tmp_path: Path) -> None:
    with pytest.raises(VoiceError, match="no such WAV file"):
        read_wav(tmp_path / "nope.wav")


def test_downsampling_does_not_fold_high_tones_into_the_speech_band() -> None:
    t = np.arange(48000) / 48000
    high = np.sin(2 * np.pi * 12000 * t).astype(np.float32)  # above the new Nyquist (8 kHz)
    assert np.sqrt(np.mean(resample(high, 48000) ** 2)) < 0.05


async def test_a_wav_source_yields_exact_chunks_with_their_times(tmp_path: Path) -> None:
    source = WavSource(_write(tmp_path, wav_bytes(tone(1.0))))
    chunks = [chunk async for chunk in source.chunks(1920)]
    assert [c.samples.size for c in chunks] == [1920] * 8 + [640]
    assert chunks[1].start == pytest.approx(0.12)
    assert chunks[1].wall - chunks[0].wall == pytest.approx(0.12)
    assert source.name.startswith("wav:") and not source.live


class FakeReachyMedia:
    """The SDK's MediaManager as the voice source uses it: 48 kHz stereo blocks and a DoA."""

    def __init__(self, blocks: list[np.ndarray]) -> None:
        self.blocks = blocks
        self.recording = False

    def start_recording(self) -> None:
        self.recording = True

    def get_audio_sample(self) -> np.ndarray | None:
        return self.blocks.pop(0) if self.blocks else None

    def get_input_audio_samplerate(self) -> int:
        return 48000

    def get_DoA(self) -> tuple[float, bool] | None:  # the SDK's name
        return (0.5, True)

    def get_frame(self) -> np.ndarray | None:
        return None


async def test_the_reachy_source_resamples_to_16khz_mono_and_gives_the_direction() -> None:
    block = np.zeros((4800, 2), np.float32)  # 0.1 s of 48 kHz stereo
    media = FakeReachyMedia([block] * 10)
    chunks = []
    async for chunk in ReachySource(media).chunks(1600):
        chunks.append(chunk)
        if len(chunks) == 5:
            break
    assert media.recording
    assert all(c.samples.size == 1600 and c.doa == 0.5 for c in chunks)


def test_reachy_without_the_sdk_says_it_is_not_importable(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "reachy_mini", None)
    with pytest.raises(VoiceError, match=r"Reachy Mini SDK.*not importable.*--source mic"):
        open_reachy_media("localhost")


async def test_the_mic_without_sounddevice_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "sounddevice", None)
    with pytest.raises(VoiceError, match=r"rosaos\[voice\]"):
        async for _ in MicSource().chunks(1920):
            pass


@pytest.mark.parametrize("rate", [48000, 44100, 22050, 8000])
def test_a_stream_resampled_in_uneven_blocks_has_no_seams(rate: int) -> None:
    t = np.arange(rate * 2) / rate
    signal = (0.5 * np.sin(2 * np.pi * 440 * t)).astype(np.float32)
    resampler, out, offset = StreamResampler(rate), [], 0
    for size in itertools.cycle([137, 2900, 480, 1001]):
        if offset >= signal.size:
            break
        out.append(resampler.push(signal[offset : offset + size]))
        offset += size
    samples = np.concatenate(out)
    assert samples.size == pytest.approx(2 * SAMPLE_RATE, abs=2)
    window = samples[2000:18000] * np.hanning(16000)
    spectrum = np.abs(np.fft.rfft(window)) ** 2
    hz = np.fft.rfftfreq(16000, 1 / SAMPLE_RATE)
    assert spectrum[(hz > 420) & (hz < 460)].sum() / spectrum.sum() > 0.999  # a click per block would spread


class FakeSoundDevice:
    """sounddevice's surface as MicSource uses it: a 48 kHz-only input that calls back from a thread."""

    class PortAudioError(Exception):
        pass

    def __init__(self) -> None:
        self.opened: list[int] = []

    def query_devices(self, kind: str) -> dict[str, object]:
        return {"name": "fake mic", "default_samplerate": 48000.0}

    def InputStream(self, samplerate: int, blocksize: int, callback: Any, **kwargs: Any) -> Any:
        if samplerate != 48000:
            raise self.PortAudioError("Invalid sample rate")
        self.opened.append(samplerate)
        return FakeStream(blocksize, callback)


class FakeStream:
    def __init__(self, blocksize: int, callback: Any) -> None:
        self.blocksize, self.callback = blocksize, callback
        self.running = False

    def __enter__(self) -> FakeStream:
        self.running = True
        threading.Thread(target=self._feed, daemon=True).start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.running = False

    def _feed(self) -> None:
        while self.running:
            self.callback(np.zeros((self.blocksize, 1), np.float32), self.blocksize, None, None)
            time.sleep(0.005)


async def test_the_mic_falls_back_to_the_device_rate_and_still_gives_16khz_chunks(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    fake = FakeSoundDevice()
    monkeypatch.setitem(sys.modules, "sounddevice", fake)
    chunks = []
    async for chunk in MicSource().chunks(1920):
        chunks.append(chunk)
        if len(chunks) == 4:
            break
    assert fake.opened == [48000]
    assert [c.samples.size for c in chunks] == [1920] * 4
    assert chunks[3].start == pytest.approx(0.36)
