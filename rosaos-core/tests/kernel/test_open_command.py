"""``rosaos open``: a fresh login link from the running kernel, printed, as JSON, or opened."""

from __future__ import annotations

import asyncio
import json
import webbrowser
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest

from rosaos.cli.open_command import open_command

from .kernel_support import TOKEN


@pytest.fixture
def config_file(tmp_path: Path) -> Path:
    """A rosaos.toml whose data directory holds the kernel's token, as `rosaos up` leaves it."""
    data = tmp_path / "data"
    data.mkdir(mode=0o700)
    (data / "token").write_text(TOKEN)
    config = tmp_path / "rosaos.toml"
    config.write_text(f'data_dir = "{data}"\n')
    return config


async def redeem(base: str, url: str) -> httpx.Response:
    code = url.split("#login=", 1)[1]
    async with httpx.AsyncClient(base_url=base) as http:
        return await http.post("/login", json={"code": code})


async def test_open_prints_a_link_that_logs_in_once(
    served: str, config_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert await _run(open_command, config_file, served, False, False) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"{served}/#login=")
    assert "valid 10 minutes" in line
    url = line.split()[0]
    assert (await redeem(served, url)).json()["token"] == TOKEN
    again = await redeem(served, url)
    assert again.status_code == 401
    assert "rosaos open" in again.json()["detail"]  # the error says how to get a new link


async def test_open_json_and_browser(
    served: str, config_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    opened: list[str] = []
    monkeypatch.setattr(webbrowser, "open", lambda url, new=0: opened.append(url) or True)
    assert await _run(open_command, config_file, served, True, True) == 0
    link = json.loads(capsys.readouterr().out)
    assert opened == [link["url"]]
    assert link["opened"] is True
    assert link["expires_in"] == 600
    assert (await redeem(served, link["url"])).status_code == 200


async def test_open_without_a_kernel_says_so(config_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert await _run(open_command, config_file, "http://127.0.0.1:9", False, False) == 2
    assert "is `rosaos up` running?" in capsys.readouterr().err


async def _run(command: Callable[..., int], *args: object) -> int:
    """open_command uses asyncio.run: run it in a thread, off this test's event loop."""
    return await asyncio.to_thread(command, *args)
