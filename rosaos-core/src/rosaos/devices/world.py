"""The world: the device instances of one configuration, resolved against the installed drivers."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from rosaos.config import ConfigError, DeviceConfig, RosaosConfig, format_validation_error
from rosaos.drivers import BackendName, DeviceContext, DriverSpec, NoticeBoard
from rosaos.plugins import DriverInfo, DriverRegistry


@dataclass(frozen=True)
class DeviceInstance:
    """One configured use of a driver, by the name the kernel sees."""

    name: str
    driver: DriverInfo
    backend: BackendName
    description: str
    settings: BaseModel
    sim: dict[str, Any] = field(default_factory=dict)
    aliases: tuple[str, ...] = ()
    area: str | None = None
    url: str | None = None
    """Set for a remote instance; local instances get their URL when served."""
    token: str | None = None
    port: int | None = None

    @property
    def spec(self) -> DriverSpec:
        return self.driver.spec

    @property
    def is_remote(self) -> bool:
        return self.url is not None

    def context(self, data_dir: Path) -> DeviceContext:
        """The context handed to the driver's backend and server factories."""
        return DeviceContext(
            instance=self.name,
            description=self.description,
            settings=self.settings,
            backend=self.backend,
            sim=self.sim,
            data_dir=data_dir,
            notices=NoticeBoard(self.name, self.spec.name, self.spec.notices),
        )


@dataclass(frozen=True)
class World:
    """Every device instance of a configuration, in a stable order."""

    instances: dict[str, DeviceInstance]
    source: Path | None
    """The config file, or None for the built-in demo world."""

    @property
    def is_demo(self) -> bool:
        return self.source is None

    def __iter__(self) -> Iterator[DeviceInstance]:
        return iter(self.instances.values())

    def __len__(self) -> int:
        return len(self.instances)

    def get(self, name: str) -> DeviceInstance:
        """The instance called ``name``, or ``KeyError`` naming the ones that exist."""
        try:
            return self.instances[name]
        except KeyError:
            known = ", ".join(self.instances) or "none"
            raise KeyError(f"unknown device {name!r}; devices in this world: {known}") from None


def build_world(config: RosaosConfig, registry: DriverRegistry) -> World:
    """Resolve ``config.devices`` (or the demo world when empty) into validated instances."""
    where = str(config.source) if config.source else "environment"
    devices = config.devices or demo_devices(registry)
    instances: dict[str, DeviceInstance] = {}
    errors: list[str] = []
    for name, device in devices.items():
        try:
            instances[name] = _resolve(name, device, registry, where)
        except ConfigError as error:
            errors.append(str(error))
    if errors:
        raise ConfigError("\n".join(errors))
    return World(instances=instances, source=config.source)


def demo_devices(registry: DriverRegistry) -> dict[str, DeviceConfig]:
    """The built-in demo world: every installed driver's demo instances, on ``sim``."""
    devices: dict[str, DeviceConfig] = {}
    for info in sorted(registry.drivers.values(), key=lambda i: (not i.spec.always_attached, i.spec.name)):
        for name, demo in info.spec.demo_instances().items():
            devices[name] = DeviceConfig(
                driver=info.spec.name,
                backend="sim",
                description=demo.description,
                sim=dict(demo.sim),
                aliases=list(demo.aliases),
                area=demo.area,
                **demo.settings,
            )
    return devices


def _resolve(name: str, device: DeviceConfig, registry: DriverRegistry, where: str) -> DeviceInstance:
    try:
        info = registry.get(device.driver)
    except KeyError as error:
        raise ConfigError(f"{where}: devices.{name}.driver: {error.args[0]}") from None
    spec = info.spec
    if device.backend not in spec.backends:
        raise ConfigError(
            f"{where}: devices.{name}.backend: driver {spec.name!r} has no {device.backend!r} backend "
            f"(it has: {', '.join(spec.backends)})"
        )
    try:
        settings = spec.settings.model_validate(device.driver_settings())
    except ValidationError as error:
        raise ConfigError(format_validation_error(where, error, prefix=f"devices.{name}")) from None
    return DeviceInstance(
        name=name,
        driver=info,
        backend=device.backend,
        description=device.description or spec.description,
        settings=settings,
        sim=dict(device.sim),
        aliases=tuple(device.aliases),
        area=device.area,
        url=device.url,
        token=device.token,
        port=device.port,
    )
