"""rosaOS's processes build no FastMCP spans, unless the user chose a telemetry mode."""

from __future__ import annotations

from collections.abc import Iterator

import fastmcp
import pytest
from fastmcp.telemetry import native_spans_enabled

from rosaos.fastmcp_spans import ENV, spans_off


@pytest.fixture(autouse=True)
def restore_mode() -> Iterator[None]:
    before = fastmcp.settings.telemetry_mode
    yield
    fastmcp.settings.telemetry_mode = before


def test_spans_are_off_once_a_rosaos_process_starts_fastmcp(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(ENV, raising=False)
    fastmcp.settings.telemetry_mode = "native"
    assert native_spans_enabled()
    spans_off()
    assert fastmcp.settings.telemetry_mode == "off"
    assert not native_spans_enabled()


@pytest.mark.parametrize("mode", ["native", "propagation_only"])
def test_a_mode_the_user_set_is_kept(monkeypatch: pytest.MonkeyPatch, mode: str) -> None:
    monkeypatch.setenv(ENV, mode)
    fastmcp.settings.telemetry_mode = mode  # FastMCP read it from the environment at import
    spans_off()
    assert fastmcp.settings.telemetry_mode == mode
