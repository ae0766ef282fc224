"""The rosaOS plugin contract: every hook a plugin may implement, in one place.

A plugin is a module registered under the ``rosaos.drivers`` entry point group. It implements
hooks by decorating functions with :data:`hookimpl`::

    from rosaos import hookimpl

    @hookimpl
    def register_drivers(register):
        register(SPEC)

Built-in drivers are registered through exactly this path, as separate distributions; rosaOS
core ships no driver of its own. :func:`rosaos.plugins.load_drivers` discovers the plugins,
calls :meth:`pluggy.PluginManager.check_pending` so a misspelled hook fails loudly at start-up,
and isolates a broken plugin so the others still load.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import pluggy

if TYPE_CHECKING:
    from rosaos.drivers import DriverSpec

PROJECT_NAME = "rosaos"
ENTRY_POINT_GROUP = "rosaos.drivers"

hookspec = pluggy.HookspecMarker(PROJECT_NAME)
hookimpl = pluggy.HookimplMarker(PROJECT_NAME)


@hookspec
def register_drivers(register: Callable[[DriverSpec], None]) -> None:
    """Declare the device drivers this plugin provides.

    Called once per plugin when rosaOS discovers its drivers: at ``rosaos up``, ``rosaos devices
    ...``, ``rosaos serve-device`` and when the conformance kit starts. Call ``register(spec)``
    once for each :class:`~rosaos.drivers.DriverSpec`; the spec's ``name`` is the driver name
    users write in ``rosaos.toml`` (``driver = "tapo"``) and should equal the entry point name.

    Return nothing. An exception raised here marks this plugin as broken: it is reported by name
    with the error, and the other plugins still load.
    """
