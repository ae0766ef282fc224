"""Fixtures for the voice tests; test modules import ``voice_support`` from this folder relatively."""

from __future__ import annotations

import pytest

from rosaos.frontends.voice.sources import Samples, read_wav

from .voice_support import ESPEAK, speak


@pytest.fixture(scope="session")
def spoken_command(tmp_path_factory: pytest.TempPathFactory) -> Samples:
    """The issue's sentence, spoken by espeak-ng in one breath."""
    if ESPEAK is None:
        pytest.skip("espeak-ng is not installed: apt-get install espeak-ng")
    path = speak("hello. turn on the kitchen light", tmp_path_factory.mktemp("speech") / "command.wav")
    return read_wav(path)
