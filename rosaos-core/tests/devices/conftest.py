"""Fixtures for the device hosting tests: every test gets its own data dir and no user config."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(autouse=True)
def isolated(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Point the data dir and the config lookup at ``tmp_path``; subprocesses inherit this."""
    monkeypatch.setenv("ROSAOS_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "share"))
    monkeypatch.delenv("ROSAOS_CONFIG", raising=False)
    monkeypatch.delenv("ROSAOS_DRIVERS", raising=False)
    monkeypatch.chdir(tmp_path)


@pytest.fixture
def data_dir(tmp_path: Path) -> Path:
    """The data dir every command and supervisor in the test uses (``$ROSAOS_DATA_DIR``)."""
    return tmp_path / "data"
