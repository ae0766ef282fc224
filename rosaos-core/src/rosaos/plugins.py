"""Driver discovery: entry points in the ``rosaos.drivers`` group, loaded through pluggy.

``ROSAOS_DRIVERS=tapo,ros`` limits which plugins load (by entry point name); unset, all load.
A plugin that fails to import, implements an unknown hook, raises in its hook, or registers an
invalid spec is reported in :attr:`DriverRegistry.broken` with its error; the others still load.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from importlib.metadata import EntryPoint, entry_points
from types import ModuleType

import pluggy
from pydantic import ValidationError

from rosaos import hookspecs
from rosaos.drivers import DriverSpec

ALLOW_ENV = "ROSAOS_DRIVERS"


@dataclass(frozen=True)
class DriverInfo:
    """A loaded driver with where it came from."""

    spec: DriverSpec
    plugin: str
    """Entry point name."""
    package: str
    """Distribution name, e.g. ``rosaos-tapo``."""
    version: str


@dataclass(frozen=True)
class BrokenPlugin:
    """A plugin that could not be loaded, and why."""

    plugin: str
    package: str
    error: str


@dataclass
class DriverRegistry:
    """The drivers installed in this environment, by driver name."""

    drivers: dict[str, DriverInfo] = field(default_factory=dict)
    broken: list[BrokenPlugin] = field(default_factory=list)

    def get(self, name: str) -> DriverInfo:
        """Return the driver called ``name``, or raise ``KeyError`` listing the installed ones."""
        try:
            return self.drivers[name]
        except KeyError:
            raise KeyError(unknown_driver_message(name, self)) from None

    @property
    def names(self) -> list[str]:
        return sorted(self.drivers)


def unknown_driver_message(name: str, registry: DriverRegistry) -> str:
    installed = ", ".join(registry.names) or "none"
    message = f"unknown driver {name!r}; installed drivers: {installed}"
    if registry.broken:
        message += "; broken plugins: " + ", ".join(b.plugin for b in registry.broken)
    return message


def allowed_plugins() -> set[str] | None:
    """The ``ROSAOS_DRIVERS`` allow-list, or None when every plugin may load."""
    raw = os.environ.get(ALLOW_ENV, "").strip()
    if not raw:
        return None
    return {name.strip() for name in raw.split(",") if name.strip()}


def _describe(error: BaseException) -> str:
    if isinstance(error, ValidationError):
        return "; ".join(
            f"{'.'.join(str(p) for p in e['loc']) or 'spec'}: {e['msg']}" for e in error.errors()
        )
    return f"{type(error).__name__}: {error}"


def load_drivers(
    allow: set[str] | None = None,
    extra_plugins: dict[str, ModuleType] | None = None,
) -> DriverRegistry:
    """Discover and load every driver plugin.

    ``allow`` overrides ``ROSAOS_DRIVERS``. ``extra_plugins`` registers modules directly by
    name, as if they came from entry points (used by tests of the loader itself).
    """
    allow = allow if allow is not None else allowed_plugins()
    registry = DriverRegistry()
    candidates: list[tuple[str, str, str, EntryPoint | ModuleType]] = []
    for ep in entry_points(group=hookspecs.ENTRY_POINT_GROUP):
        dist = ep.dist
        candidates.append(
            (ep.name, dist.name if dist else "?", dist.version if dist else "?", ep),
        )
    for name, module in (extra_plugins or {}).items():
        candidates.append((name, module.__name__, "0", module))

    for plugin_name, package, version, source in sorted(candidates, key=lambda c: c[0]):
        if allow is not None and plugin_name not in allow:
            continue
        try:
            module = source.load() if isinstance(source, EntryPoint) else source
            specs = _call_register(plugin_name, module)
        except Exception as error:  # one broken plugin must not take the others down
            registry.broken.append(BrokenPlugin(plugin_name, package, _describe(error)))
            continue
        for spec in specs:
            if spec.name in registry.drivers:
                other = registry.drivers[spec.name]
                registry.broken.append(
                    BrokenPlugin(
                        plugin_name, package, f"driver {spec.name!r} is already provided by {other.package}"
                    )
                )
                continue
            registry.drivers[spec.name] = DriverInfo(spec, plugin_name, package, version)
    return registry


def _call_register(plugin_name: str, module: object) -> list[DriverSpec]:
    """Run one plugin's hooks in a plugin manager of its own, so its failure stays its own."""
    manager = pluggy.PluginManager(hookspecs.PROJECT_NAME)
    manager.add_hookspecs(hookspecs)
    manager.register(module, name=plugin_name)
    manager.check_pending()
    collected: list[DriverSpec] = []

    def register(spec: DriverSpec) -> None:
        if not isinstance(spec, DriverSpec):
            raise TypeError(f"register() takes a DriverSpec, got {type(spec).__name__}")
        collected.append(spec)

    manager.hook.register_drivers(register=register)
    if not collected:
        raise RuntimeError("plugin registered no driver: call register(spec) in register_drivers")
    return collected
