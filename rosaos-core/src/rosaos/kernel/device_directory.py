"""The world's devices as the kernel grants them: one :class:`DeviceEndpoint` per instance.

The device hosting (host processes in ``rosaos up``, in-process simulators in the benchmark) says
where each device is served and whether it is up; the world and the config add its driver, prompt
and confirmation rule. :class:`DeviceDirectory` joins the two, and builds the result again only
when the hosting's ``version`` says a device changed: a burst of events then costs no walk over a
hundred devices each.
"""

from __future__ import annotations

from rosaos.config import RosaosConfig
from rosaos.confirmations.confirming import ConfirmRule, confirm_rule
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.hosting import DeviceHosting
from rosaos.devices.world import World


class DeviceDirectory:
    """Call it for the current endpoints, by instance name (callers must not mutate the dict)."""

    def __init__(self, hosting: DeviceHosting, world: World, config: RosaosConfig, token: str) -> None:
        self._hosting = hosting
        self._world = world
        self._config = config
        self._token = token
        self._cached: tuple[int, dict[str, DeviceEndpoint]] | None = None

    def __call__(self) -> dict[str, DeviceEndpoint]:
        version = self._hosting.version
        if self._cached is not None and self._cached[0] == version:
            return self._cached[1]
        endpoints = {}
        for name, entry in self._hosting.directory().items():
            instance = self._world.instances[name]
            spec = instance.spec
            endpoints[name] = DeviceEndpoint(
                name=name,
                driver=spec.name,
                concurrency=spec.concurrency,
                always_attached=spec.always_attached,
                description=instance.description,
                prompt=spec.prompt,
                url=entry.url,
                token=entry.token or self._token,
                status=entry.status,
                confirm=self._confirm_rule(name),
                attached_tools=tuple(spec.attached_tools),
                attached_prompt=spec.attached_prompt,
                attached_pattern=spec.attached_pattern,
                on_request_tools=tuple(spec.on_request_tools),
                on_request_pattern=spec.on_request_pattern,
                host=self._hosting.host_of(name),
                server_epoch=entry.server_epoch,
            )
        self._cached = (version, endpoints)
        return endpoints

    def _confirm_rule(self, name: str) -> ConfirmRule:
        instance, configured = self._world.instances[name], self._config.devices.get(name)
        own = configured.confirm if configured is not None else None
        return confirm_rule(own, self._config.confirm, instance.backend, instance.spec.confirm_on_real)
