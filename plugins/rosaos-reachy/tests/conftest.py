"""Fixtures shared by the reachy tests; helpers live in ``reachy_support.py``."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator

import pytest

# Test modules import reachy_support by name (pytest's importlib mode puts no test dir on sys.path).
HERE = os.path.dirname(__file__)
if HERE not in sys.path:
    sys.path.insert(0, HERE)

from reachy_support import CLOUD_KEYS, FakeOpenAI, serve_fake_openai  # noqa: E402


@pytest.fixture(autouse=True)
def _no_cloud_keys(monkeypatch: pytest.MonkeyPatch) -> None:
    """Tests never reach a cloud service, whatever keys the developer's shell holds."""
    for key in CLOUD_KEYS:
        monkeypatch.delenv(key, raising=False)


@pytest.fixture
def fake_openai() -> Iterator[FakeOpenAI]:
    """A fake OpenAI-compatible service on loopback (chat completions and speech)."""
    with serve_fake_openai() as fake:
        yield fake
