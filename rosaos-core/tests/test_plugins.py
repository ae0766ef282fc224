"""Driver discovery (rosaos.plugins): the allow-list, and broken plugins isolated and reported by name."""

from __future__ import annotations

from collections.abc import Callable
from importlib.metadata import EntryPoint
from types import ModuleType
from typing import Any

import pytest
from fastmcp import FastMCP

from rosaos import hookimpl, plugins
from rosaos.drivers import DeviceBackend, DeviceContext, DriverSpec
from rosaos.plugins import load_drivers

Register = Callable[[DriverSpec], None]


def make_spec(name: str, **overrides: Any) -> DriverSpec:
    """A minimal valid spec for a fake driver."""
    fields: dict[str, Any] = {
        "name": name,
        "title": f"Fake {name}",
        "description": f"A fake {name} device.",
        "concurrency": "exclusive",
        "prompt": f"You control the fake {name}.",
        "server": lambda ctx, backend: FastMCP(ctx.instance),
        "backends": {"sim": lambda ctx: DeviceBackend()},
    }
    return DriverSpec(**(fields | overrides))


def plugin_module(module_name: str, register_drivers: Callable[[Register], None]) -> ModuleType:
    """A module implementing ``register_drivers``, as a plugin package would."""
    module = ModuleType(module_name)
    module.register_drivers = hookimpl(register_drivers)  # type: ignore[attr-defined]
    return module


def registering(*names: str) -> Callable[[Register], None]:
    def register_drivers(register: Register) -> None:
        for name in names:
            register(make_spec(name))

    return register_drivers


def good(name: str) -> ModuleType:
    return plugin_module(f"fake_{name}", registering(name))


def test_every_plugin_loads_without_an_allow_list(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(plugins.ALLOW_ENV, raising=False)
    registry = load_drivers(extra_plugins={"alpha": good("alpha"), "beta": good("beta")})
    assert {"alpha", "beta"} <= set(registry.names)


def test_rosaos_drivers_limits_which_plugins_load(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(plugins.ALLOW_ENV, " alpha , ")
    registry = load_drivers(extra_plugins={"alpha": good("alpha"), "beta": good("beta")})
    assert registry.names == ["alpha"]


def test_allow_argument_wins_over_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(plugins.ALLOW_ENV, "alpha")
    registry = load_drivers(allow={"beta"}, extra_plugins={"alpha": good("alpha"), "beta": good("beta")})
    assert registry.names == ["beta"]


def test_a_plugin_that_raises_is_reported_by_name_and_the_others_load() -> None:
    def register_drivers(register: Register) -> None:
        raise RuntimeError("cannot reach the vendor SDK")

    registry = load_drivers(
        allow={"alpha", "broken"},
        extra_plugins={"alpha": good("alpha"), "broken": plugin_module("fake_broken", register_drivers)},
    )
    assert registry.names == ["alpha"]
    assert [(b.plugin, b.error) for b in registry.broken] == [
        ("broken", "RuntimeError: cannot reach the vendor SDK")
    ]


def test_a_plugin_that_fails_to_import_is_reported_by_name(monkeypatch: pytest.MonkeyPatch) -> None:
    missing = EntryPoint(name="ghost", value="rosaos_no_such_module.plugin", group="rosaos.drivers")
    monkeypatch.setattr(plugins, "entry_points", lambda group: [missing])
    registry = load_drivers(allow={"ghost", "alpha"}, extra_plugins={"alpha": good("alpha")})
    assert registry.names == ["alpha"]
    assert registry.broken[0].plugin == "ghost"
    assert "ModuleNotFoundError" in registry.broken[0].error


def test_an_invalid_spec_is_reported_with_the_field() -> None:
    def register_drivers(register: Register) -> None:
        register(make_spec("bad", backends={"real": lambda ctx: DeviceBackend()}))

    registry = load_drivers(allow={"bad"}, extra_plugins={"bad": plugin_module("fake_bad", register_drivers)})
    assert registry.names == []
    assert "no 'sim' backend" in registry.broken[0].error


def test_a_misspelled_hookimpl_is_caught_by_check_pending() -> None:
    module = ModuleType("fake_typo")
    module.register_driver = hookimpl(registering("typo"))  # type: ignore[attr-defined]
    registry = load_drivers(allow={"typo"}, extra_plugins={"typo": module})
    assert registry.names == []
    assert registry.broken[0].plugin == "typo"
    assert "register_driver" in registry.broken[0].error


def test_a_plugin_that_registers_nothing_is_broken() -> None:
    registry = load_drivers(
        allow={"empty"}, extra_plugins={"empty": plugin_module("fake_empty", registering())}
    )
    assert "registered no driver" in registry.broken[0].error


def test_register_refuses_what_is_not_a_spec() -> None:
    def register_drivers(register: Callable[[object], None]) -> None:
        register({"name": "dict_driver"})

    registry = load_drivers(allow={"odd"}, extra_plugins={"odd": plugin_module("fake_odd", register_drivers)})
    assert "takes a DriverSpec, got dict" in registry.broken[0].error


def test_a_duplicate_driver_name_keeps_the_first_and_reports_the_second() -> None:
    registry = load_drivers(
        allow={"first", "second"},
        extra_plugins={
            "first": plugin_module("pkg_first", registering("lamp")),
            "second": plugin_module("pkg_second", registering("lamp")),
        },
    )
    assert registry.get("lamp").plugin == "first"
    assert [(b.plugin, b.error) for b in registry.broken] == [
        ("second", "driver 'lamp' is already provided by pkg_first")
    ]


def test_an_unknown_driver_lists_the_installed_and_the_broken_ones() -> None:
    def register_drivers(register: Register) -> None:
        raise ImportError("no SDK")

    registry = load_drivers(
        allow={"alpha", "broken"},
        extra_plugins={"alpha": good("alpha"), "broken": plugin_module("fake_broken", register_drivers)},
    )
    with pytest.raises(KeyError) as raised:
        registry.get("lampp")
    assert raised.value.args[0] == "unknown driver 'lampp'; installed drivers: alpha; broken plugins: broken"


def test_one_plugin_may_register_several_drivers() -> None:
    registry = load_drivers(
        allow={"multi"}, extra_plugins={"multi": plugin_module("fake_multi", registering("a", "b"))}
    )
    assert registry.names == ["a", "b"]
    assert {info.plugin for info in registry.drivers.values()} == {"multi"}


def test_demo_instances_default_to_one_named_after_the_driver() -> None:
    spec = make_spec("lamp")
    assert list(spec.demo_instances()) == ["lamp"]
    assert spec.demo_instances()["lamp"].description == "A fake lamp device."


def test_the_spec_rejects_a_bad_driver_name() -> None:
    with pytest.raises(ValueError, match="must match"):
        make_spec("Kitchen-Light")


def test_device_context_puts_images_in_the_data_dir(tmp_path: Any) -> None:
    ctx = DeviceContext(
        instance="cam", description="", settings=make_spec("x").settings(), backend="sim", data_dir=tmp_path
    )
    assert ctx.images_dir == tmp_path / "images"
