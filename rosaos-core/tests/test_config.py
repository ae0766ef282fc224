"""Configuration (rosaos.config) and the world it describes (rosaos.devices.world)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest
from fastmcp import FastMCP
from pydantic import Field

from rosaos.config import CONFIG_ENV, ConfigError, DeviceConfig, RosaosConfig, load_config
from rosaos.devices.world import build_world
from rosaos.drivers import DemoInstance, DeviceBackend, DeviceSettings, DriverSpec
from rosaos.plugins import DriverInfo, DriverRegistry


@pytest.fixture(autouse=True)
def isolated(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """No ROSAOS_* variable from the developer's shell; empty cwd and user config dir."""
    for variable in [v for v in os.environ if v.startswith("ROSAOS_")]:
        monkeypatch.delenv(variable)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "xdg-config"))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg-data"))
    workdir = tmp_path / "work"
    workdir.mkdir()
    monkeypatch.chdir(workdir)
    return tmp_path


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def port_file(path: Path, port: int) -> Path:
    return write(path, f"[kernel]\nport = {port}\n")


def user_config(tmp_path: Path) -> Path:
    return tmp_path / "xdg-config" / "rosaos" / "rosaos.toml"


# Where the file comes from


def test_explicit_config_wins_over_env_cwd_and_user_dir(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(CONFIG_ENV, str(port_file(tmp_path / "env.toml", 1002)))
    port_file(Path("rosaos.toml"), 1003)
    port_file(user_config(tmp_path), 1004)
    assert load_config(port_file(tmp_path / "explicit.toml", 1001)).kernel.port == 1001


def test_rosaos_config_env_wins_over_cwd_and_user_dir(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(CONFIG_ENV, str(port_file(tmp_path / "env.toml", 1002)))
    port_file(Path("rosaos.toml"), 1003)
    port_file(user_config(tmp_path), 1004)
    assert load_config().kernel.port == 1002


def test_cwd_file_wins_over_user_dir(tmp_path: Path) -> None:
    port_file(Path("rosaos.toml"), 1003)
    port_file(user_config(tmp_path), 1004)
    assert load_config().kernel.port == 1003


def test_user_dir_file_is_the_last_resort(tmp_path: Path) -> None:
    config = load_config_from(port_file(user_config(tmp_path), 1004))
    assert (config.kernel.port, config.source) == (1004, user_config(tmp_path))


def load_config_from(expected_source: Path) -> RosaosConfig:
    config = load_config()
    assert config.source == expected_source
    return config


def test_no_file_means_defaults_and_no_devices() -> None:
    config = load_config()
    assert (config.source, config.devices, config.kernel.port) == (None, {}, 8765)


def test_a_missing_explicit_file_is_an_error() -> None:
    with pytest.raises(ConfigError, match=r"nope\.toml: no such config file"):
        load_config(Path("nope.toml"))


def test_a_missing_rosaos_config_file_is_an_error_naming_the_variable(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv(CONFIG_ENV, "gone.toml")
    with pytest.raises(ConfigError, match=r"gone.toml: no such config file \(from \$ROSAOS_CONFIG\)"):
        load_config()


# Values


def test_environment_overrides_the_file(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROSAOS_KERNEL__PORT", "9000")
    config = load_config(port_file(Path("rosaos.toml"), 1003))
    assert config.kernel.port == 9000


def test_an_unknown_key_names_file_key_and_reason() -> None:
    path = write(Path("rosaos.toml").absolute(), "[kernel]\nprot = 9000\n")
    with pytest.raises(ConfigError) as raised:
        load_config()
    assert str(raised.value) == f"{path}: kernel.prot: Extra inputs are not permitted"


def test_an_out_of_range_value_names_file_key_and_reason() -> None:
    path = write(Path("rosaos.toml").absolute(), "[kernel]\nport = 70000\n")
    with pytest.raises(ConfigError) as raised:
        load_config()
    assert str(raised.value) == f"{path}: kernel.port: Input should be less than or equal to 65535"


def test_invalid_toml_names_the_file() -> None:
    write(Path("rosaos.toml"), "[kernel\n")
    with pytest.raises(ConfigError, match=r"rosaos.toml: not valid TOML"):
        load_config()


def test_device_tables_keep_the_driver_settings_apart() -> None:
    write(Path("rosaos.toml"), '[devices.lamp]\ndriver = "lamp"\nhost = "10.0.0.5"\nsim = { on = true }\n')
    device = load_config().devices["lamp"]
    assert (device.backend, device.driver_settings(), device.sim) == (
        "sim",
        {"host": "10.0.0.5"},
        {"on": True},
    )


# The world


class LampSettings(DeviceSettings):
    host: str | None = None
    timeout: float = Field(default=5.0, gt=0, le=60)


def fake_driver(name: str, **overrides: Any) -> DriverInfo:
    fields: dict[str, Any] = {
        "name": name,
        "title": f"Fake {name}",
        "description": f"A fake {name}.",
        "concurrency": "exclusive",
        "prompt": "Fake.",
        "settings": LampSettings,
        "server": lambda ctx, backend: FastMCP(ctx.instance),
        "backends": {"sim": lambda ctx: DeviceBackend()},
    }
    return DriverInfo(DriverSpec(**(fields | overrides)), name, f"rosaos-{name}", "0.1.0")


def registry(*infos: DriverInfo) -> DriverRegistry:
    return DriverRegistry(drivers={info.spec.name: info for info in infos})


def config_with(**devices: dict[str, Any]) -> RosaosConfig:
    config = RosaosConfig(devices={name: DeviceConfig(**table) for name, table in devices.items()})
    config._source = Path("/etc/rosaos.toml")
    return config


def test_an_unknown_driver_lists_the_installed_drivers() -> None:
    config = config_with(fridge={"driver": "fridge"})
    with pytest.raises(ConfigError) as raised:
        build_world(config, registry(fake_driver("lamp"), fake_driver("robot")))
    assert str(raised.value) == (
        "/etc/rosaos.toml: devices.fridge.driver: unknown driver 'fridge'; installed drivers: lamp, robot"
    )


def test_no_devices_means_the_demo_world_on_sim() -> None:
    ui = fake_driver("ui", always_attached=True, concurrency="shared")
    lamp = fake_driver(
        "lamp",
        demo={
            "kitchen_light": DemoInstance(description="Kitchen", sim={"on": False}),
            "porch_light": DemoInstance(description="Porch", settings={"host": "10.0.0.9"}),
        },
    )
    world = build_world(RosaosConfig(), registry(lamp, ui))
    assert world.is_demo
    assert [(i.name, i.backend, i.description) for i in world] == [
        ("ui", "sim", "A fake ui."),  # the always-attached device comes first
        ("kitchen_light", "sim", "Kitchen"),
        ("porch_light", "sim", "Porch"),
    ]
    assert world.get("kitchen_light").sim == {"on": False}
    assert world.get("porch_light").settings == LampSettings(host="10.0.0.9")


def test_driver_settings_are_validated_against_the_spec_settings_model() -> None:
    config = config_with(lamp={"driver": "lamp", "timeout": 0, "colour": "red"})
    with pytest.raises(ConfigError) as raised:
        build_world(config, registry(fake_driver("lamp")))
    assert str(raised.value).splitlines() == [
        "/etc/rosaos.toml: devices.lamp.timeout: Input should be greater than 0",
        "/etc/rosaos.toml: devices.lamp.colour: Extra inputs are not permitted",
    ]


def test_valid_settings_reach_the_instance_as_the_settings_model() -> None:
    config = config_with(lamp={"driver": "lamp", "host": "10.0.0.5", "description": "Desk lamp"})
    instance = build_world(config, registry(fake_driver("lamp"))).get("lamp")
    assert (instance.settings, instance.description) == (LampSettings(host="10.0.0.5"), "Desk lamp")


def test_a_backend_the_driver_lacks_is_an_error_listing_the_ones_it_has() -> None:
    config = config_with(lamp={"driver": "lamp", "backend": "real"})
    with pytest.raises(
        ConfigError, match=r"devices.lamp.backend: driver 'lamp' has no 'real' backend \(it has: sim\)"
    ):
        build_world(config, registry(fake_driver("lamp")))


def test_every_bad_device_is_reported_at_once() -> None:
    config = config_with(a={"driver": "nope"}, b={"driver": "lamp", "timeout": "x"})
    with pytest.raises(ConfigError) as raised:
        build_world(config, registry(fake_driver("lamp")))
    assert [line.split(": ")[1] for line in str(raised.value).splitlines()] == [
        "devices.a.driver",
        "devices.b.timeout",
    ]


def test_an_unknown_device_name_lists_the_devices() -> None:
    world = build_world(config_with(lamp={"driver": "lamp"}), registry(fake_driver("lamp")))
    with pytest.raises(KeyError, match="unknown device 'lump'; devices in this world: lamp"):
        world.get("lump")
