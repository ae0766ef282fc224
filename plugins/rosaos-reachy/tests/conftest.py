"""Fixtures shared by the reachy tests; helpers live in ``reachy_support.py``."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from .reachy_support import CLOUD_KEYS, FakeOpenAI, serve_fake_openai


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
