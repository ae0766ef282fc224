"""Audio for the voice tests: tones, silence and (where espeak-ng is installed) speech."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from rosaos.frontends.voice.sources import SAMPLE_RATE, AudioChunk, Samples

ESPEAK = shutil.which("espeak-ng")
needs_espeak = pytest.mark.skipif(
    ESPEAK is None, reason="espeak-ng is not installed: apt-get install espeak-ng (scripts/bootstrap.sh does)"
)


def tone(seconds: float, hz: float = 440.0, level: float = 0.3) -> Samples:
    t = np.arange(round(seconds * SAMPLE_RATE)) / SAMPLE_RATE
    return (level * np.sin(2 * np.pi * hz * t)).astype(np.float32)


def silence(seconds: float) -> Samples:
    return np.zeros(round(seconds * SAMPLE_RATE), np.float32)


def pattern(*parts: tuple[str, float]) -> Samples:
    """("tone", 1.0), ("silence", 0.5), ...: a test signal from labelled pieces."""
    return np.concatenate([tone(s) if kind == "tone" else silence(s) for kind, s in parts])


def chunks_of(samples: Samples, chunk_seconds: float = 0.12, wall0: float = 1_000.0) -> list[AudioChunk]:
    size = round(chunk_seconds * SAMPLE_RATE)
    return [
        AudioChunk(samples[i : i + size], i / SAMPLE_RATE, wall0 + i / SAMPLE_RATE)
        for i in range(0, samples.size, size)
    ]


def speak(text: str, path: Path, *args: str) -> Path:
    """espeak-ng's default voice saying ``text`` into a WAV file (22.05 kHz, as espeak writes it)."""
    assert ESPEAK is not None
    subprocess.run([ESPEAK, *args, "-w", str(path), text], check=True)
    return path
