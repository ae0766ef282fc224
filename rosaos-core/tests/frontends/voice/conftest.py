"""Fixtures for the voice tests. Test modules import voice_support from this folder (pytest's
importlib mode does not put it on sys.path)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

HERE = str(Path(__file__).parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)

from voice_support import ESPEAK, speak  # noqa: E402

from rosaos.frontends.voice.sources import Samples, read_wav  # noqa: E402


@pytest.fixture(scope="session")
def spoken_command(tmp_path_factory: pytest.TempPathFactory) -> Samples:
    """The issue's sentence, spoken by espeak-ng in one breath."""
    if ESPEAK is None:
        pytest.skip("espeak-ng is not installed: apt-get install espeak-ng")
    path = speak("hello. turn on the kitchen light", tmp_path_factory.mktemp("speech") / "command.wav")
    return read_wav(path)
