"""``rosaos devices list``, ``rosaos devices check`` and ``rosaos serve-device``, as a user runs them.

The CLI runs as a subprocess where the process boundary matters (``serve-device``); the other
commands run in this process through typer's ``CliRunner``, and quick error paths call the
command functions directly. Every test has its own data dir (``$ROSAOS_DATA_DIR``) and config.
"""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest

from rosaos.auth import token_path
from rosaos.cli.device_commands import check_device, list_devices, serve_device_command
from rosaos.plugins import load_drivers

from .devices_support import ROSAOS, closed_port_url, free_port, requires_tapo, rosaos, write_config

pytestmark = [pytest.mark.slow, requires_tapo]

KITCHEN = """
[devices.kitchen_light]
driver = "tapo"
description = "Ceiling light in the kitchen"
sim = { on = true, brightness = 30 }
"""


def far_lamp(url: str) -> str:
    return f'\n[devices.far_lamp]\ndriver = "tapo"\nurl = "{url}"\n'


@pytest.fixture
def config(tmp_path: Path, data_dir: Path) -> Path:
    return write_config(tmp_path / "rosaos.toml", data_dir, KITCHEN)


@dataclass
class ServedLight:
    process: subprocess.Popen[str]
    url: str
    data_dir: Path
    config: Path

    @property
    def env(self) -> dict[str, str]:
        return {"ROSAOS_DATA_DIR": str(self.data_dir)}


def start_serve_device(config: Path, data_dir: Path) -> ServedLight:
    """Run ``rosaos serve-device kitchen_light`` and wait until /health answers."""
    port = free_port()
    process = subprocess.Popen(
        [str(ROSAOS), "serve-device", "kitchen_light", "--config", str(config), "--port", str(port)],
        env=os.environ | {"ROSAOS_DATA_DIR": str(data_dir)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    url = f"http://127.0.0.1:{port}/mcp"
    deadline = time.monotonic() + 60
    while True:
        assert process.poll() is None, process.communicate()
        try:
            if httpx.get(f"http://127.0.0.1:{port}/health", timeout=1).status_code == 200:
                break
        except httpx.HTTPError:
            pass
        assert time.monotonic() < deadline, "serve-device did not come up within 60 s"
        time.sleep(0.05)
    # /health answers a moment before the served-device record is written.
    while not (data_dir / "run" / "serve-device" / "kitchen_light.json").exists():
        assert time.monotonic() < deadline, "serve-device did not record itself"
        time.sleep(0.05)
    return ServedLight(process, url, data_dir, config)


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ServedLight]:
    """One ``rosaos serve-device`` for the tests that only talk to it."""
    root = tmp_path_factory.mktemp("served")
    light = start_serve_device(write_config(root / "rosaos.toml", root / "data", KITCHEN), root / "data")
    yield light
    light.process.send_signal(signal.SIGINT)
    try:
        light.process.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        light.process.kill()
        light.process.communicate()


# --- devices list -------------------------------------------------------------------------------


def test_list_json_reports_each_instance_and_exits_0_even_if_one_is_unreachable(
    tmp_path: Path, data_dir: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, KITCHEN + far_lamp(closed_port_url()))
    result = rosaos("devices", "list", "--json", "--config", str(config))
    assert result.returncode == 0, result.stderr
    rows = {row["instance"]: row for row in json.loads(result.stdout)}
    assert rows["kitchen_light"] | {"state": None} == {
        "instance": "kitchen_light",
        "driver": "tapo",
        "package": "rosaos-tapo",
        "version": load_drivers().get("tapo").version,
        "concurrency": "exclusive",
        "backend": "sim",
        "url": None,
        "health": "healthy (not served)",
        "state": None,
        "via": "in-process",
    }
    assert rows["kitchen_light"]["state"]["brightness"] == 30
    assert rows["far_lamp"]["health"].startswith("error: nothing is listening at")
    assert rows["far_lamp"]["via"] == "remote"


def test_list_probes_a_served_instance_at_its_url(
    served: ServedLight, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ROSAOS_DATA_DIR", str(served.data_dir))
    assert list_devices(served.config, json_output=True, check=True) == 0
    [row] = json.loads(capsys.readouterr().out)
    assert (row["url"], row["via"]) == (served.url, "served")
    assert row["health"] == "healthy"


PLACEHOLDER_MODULE = """
from fastmcp import FastMCP
from rosaos import hookimpl
from rosaos.drivers import DeviceError, DriverSpec


def _sim(ctx):
    raise DeviceError("someday is not implemented yet")


SPEC = DriverSpec(
    name="someday", title="Someday", description="A driver not written yet.", concurrency="exclusive",
    prompt="Not yet.", server=lambda ctx, backend: FastMCP("someday"), backends={"sim": _sim},
    implemented=False,
)


@hookimpl
def register_drivers(register):
    register(SPEC)
"""


@pytest.fixture
def placeholder_driver(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """A placeholder driver installed the way pip would: a module plus a dist-info with its entry point."""
    site = tmp_path / "site"
    dist = site / "rosaos_test_placeholder-0.1.dist-info"
    dist.mkdir(parents=True)
    (site / "rosaos_test_placeholder.py").write_text(PLACEHOLDER_MODULE)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: rosaos-test-placeholder\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[rosaos.drivers]\nsomeday = rosaos_test_placeholder\n")
    monkeypatch.syspath_prepend(str(site))
    assert not load_drivers().get("someday").spec.implemented
    return "someday"


def test_list_table_shows_placeholders_as_not_implemented(
    tmp_path: Path,
    data_dir: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    placeholder_driver: str,
) -> None:
    body = KITCHEN + f'\n[devices.someday]\ndriver = "{placeholder_driver}"\n'
    monkeypatch.setenv("COLUMNS", "200")
    assert list_devices(write_config(tmp_path / "rosaos.toml", data_dir, body), check=True) == 0
    out = capsys.readouterr().out
    assert "healthy (not served)" in out
    assert "not implemented" in out


def test_an_unknown_driver_exits_2_naming_the_installed_drivers(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, '[devices.lamp]\ndriver = "nope"\n')
    assert list_devices(config) == 2
    err = capsys.readouterr().err
    assert "devices.lamp.driver: unknown driver 'nope'; installed drivers:" in err
    assert "tapo" in err


# --- devices check ------------------------------------------------------------------------------


def test_check_starts_an_unserved_instance_in_process_and_says_so(config: Path) -> None:
    result = rosaos("devices", "check", "kitchen_light", "--config", str(config))
    assert result.returncode == 0, result.stderr
    headline, _, state = result.stdout.partition("\n")
    assert headline.startswith("kitchen_light: healthy, checked in this process")
    assert json.loads(state)["brightness"] == 30


def test_check_goes_to_the_served_url(served: ServedLight) -> None:
    result = rosaos(
        "devices", "check", "kitchen_light", "--json", "--config", str(served.config), env=served.env
    )
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert (report["via"], report["url"], report["ok"]) == ("served", served.url, True)
    assert report["state"]["on"] is True


def test_an_unreachable_device_fails_fast_with_how_to_start_it(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = closed_port_url()
    config = write_config(tmp_path / "rosaos.toml", data_dir, far_lamp(url))
    started = time.monotonic()
    assert check_device("far_lamp", config, timeout=10) == 1
    assert time.monotonic() - started < 3
    assert capsys.readouterr().err == (
        f"far_lamp: check failed: nothing is listening at {url}: "
        "is `rosaos up` or `rosaos serve-device far_lamp` running?\n"
    )


def test_check_of_an_unknown_name_lists_the_known_ones(
    config: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert check_device("garage_door", config) == 1
    assert "unknown device 'garage_door'; devices in this world: kitchen_light" in capsys.readouterr().err


def test_check_of_a_placeholder_says_not_implemented(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], placeholder_driver: str
) -> None:
    config = write_config(
        tmp_path / "rosaos.toml", data_dir, f'[devices.bot]\ndriver = "{placeholder_driver}"\n'
    )
    assert check_device("bot", config) == 1
    assert "is not implemented yet" in capsys.readouterr().err


# --- serve-device -------------------------------------------------------------------------------


def test_a_request_without_the_token_gets_401(served: ServedLight) -> None:
    response = httpx.post(served.url, json={"jsonrpc": "2.0", "id": 1, "method": "ping"})
    assert response.status_code == 401
    assert "bearer token" in response.json()["detail"]


def test_the_token_file_is_owner_only(served: ServedLight) -> None:
    assert stat.S_IMODE(token_path(served.data_dir).stat().st_mode) == 0o600


def test_serve_device_prints_its_url_and_stops_cleanly_on_ctrl_c(config: Path, data_dir: Path) -> None:
    light = start_serve_device(config, data_dir)
    light.process.send_signal(signal.SIGINT)
    out, err = light.process.communicate(timeout=15)
    assert light.process.returncode == 0, err
    assert f"kitchen_light (tapo, sim) serving at {light.url}" in out
    assert f"token: {token_path(data_dir)}" in out
    assert not (data_dir / "run" / "serve-device" / "kitchen_light.json").exists()


def test_serve_device_warns_off_loopback_and_explains_a_busy_port(
    config: Path, served: ServedLight, capsys: pytest.CaptureFixture[str]
) -> None:
    busy = int(served.url.split(":")[2].split("/")[0])
    assert serve_device_command("kitchen_light", config, host="0.0.0.0", port=busy) == 1
    err = capsys.readouterr().err
    assert "not loopback" in err
    assert f"cannot bind 0.0.0.0:{busy}" in err
    assert "pick another --port" in err
