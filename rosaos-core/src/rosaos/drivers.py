"""What a driver declares: :class:`DriverSpec`, and the types its factories receive and return.

A driver is three factories and some data:

- ``settings``: a pydantic model for one device instance (host, credentials, profile, ...).
- ``backends``: ``{"sim": ..., "real": ...}``, each building a :class:`DeviceBackend` from a
  :class:`DeviceContext`. ``sim`` is mandatory: every driver runs with no hardware.
- ``server``: builds the instance's FastMCP server from the context and the backend.

The hosting layer (:mod:`rosaos.devices`) owns the lifecycle: it validates settings, builds the
backend, calls ``await backend.start()``, builds the server, serves it, and on shutdown calls
``await backend.close()``. An emergency stop calls ``spec.safe_stop(backend)``, also exposed to
clients as the ``safe_stop`` tool that the hosting layer adds to every device server.
"""

from __future__ import annotations

import re
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Generic, Literal, Self

from fastmcp import FastMCP
from mcp.types import ToolAnnotations
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from typing_extensions import TypeVar

from rosaos.cards import Card

# Re-exported: notices are part of the driver contract.
from rosaos.notices.notice_board import Notice as Notice
from rosaos.notices.notice_board import NoticeBoard as NoticeBoard
from rosaos.notices.notice_board import NoticeError as NoticeError
from rosaos.notices.notice_board import NoticeImportance as NoticeImportance
from rosaos.notices.notice_board import NoticeSpec as NoticeSpec

Concurrency = Literal["exclusive", "shared"]
"""How many live processes may hold one instance: ``exclusive`` means one, ``shared`` any."""

BackendName = Literal["sim", "real"]

Halt = Literal["motion", "speech", "sound"]
"""What a device's ``safe_stop`` ends, in the order a bare "stop" ends them (``DriverSpec.halts``)."""

DRIVER_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


class DeviceSettings(BaseModel):
    """Base class for a driver's per-instance settings. Unknown keys are an error, not ignored."""

    model_config = ConfigDict(extra="forbid")


class DeviceBackend:
    """Base class for a driver backend: the object that talks to the device (or simulates it).

    Override :meth:`start` and :meth:`close` when the backend holds a connection or a subprocess.
    Blocking SDK calls belong in a thread (``asyncio.to_thread``), never on the event loop.
    """

    simulated: bool = False
    """True for the ``sim`` backend; shown by ``rosaos devices list``."""

    async def start(self) -> None:
        """Connect or start the simulator. Raise :class:`DeviceError` with a fix-it message."""

    async def close(self) -> None:
        """Release connections and subprocesses. Called once, also after a failed start."""


class DeviceError(Exception):
    """A device-level failure whose message says what happened and what to try.

    Tools let it propagate (FastMCP turns it into a tool error the model can read); the CLI
    prints it without a traceback.
    """


SettingsT = TypeVar("SettingsT", bound=BaseModel, default=Any)
"""A driver's settings class. The hosting layer validates an instance's settings with
``spec.settings``, so a factory typed ``DeviceContext[TapoSettings]`` reads ``ctx.settings`` as a
``TapoSettings``, with no check or cast of its own. Unparameterized (the hosting layer, which
serves any driver): any settings."""


@dataclass(frozen=True)
class DeviceContext(Generic[SettingsT]):
    """Everything a backend or server factory gets to know about the instance it builds.

    Generic in the driver's settings class: ``DeviceContext[TapoSettings]``, or
    ``DeviceContext[DeviceSettings]`` for a driver with none."""

    instance: str
    """The instance name the kernel sees, e.g. ``kitchen_light``."""
    description: str
    settings: SettingsT
    """The validated ``spec.settings`` model for this instance."""
    backend: BackendName
    sim: Mapping[str, Any] = field(default_factory=dict)
    """Initial simulator state and sim-only settings (the ``sim`` table of the instance)."""
    data_dir: Path = Path(".")
    """The rosaOS data directory; per-driver caches go in ``data_dir / "drivers" / <driver>``."""

    notices: NoticeBoard = field(default_factory=NoticeBoard, compare=False, repr=False)
    """Where :meth:`notify` posts; the hosting layer serves it to the kernel at ``GET /notices``."""

    @property
    def images_dir(self) -> Path:
        """Shared directory for images (camera captures) that tools return by relative path."""
        return self.data_dir / "images"

    def notify(
        self,
        name: str,
        data: Mapping[str, Any] | None = None,
        *,
        message: str | None = None,
        importance: NoticeImportance | None = None,
    ) -> Notice:
        """Tell the kernel something happened on this device: it becomes a ``[Device notice]`` event.

        ``name`` must be declared in ``DriverSpec.notices`` and ``data`` must validate against
        its model (else :class:`NoticeError`). ``message`` is one sentence a person can hear
        (default "<instance>: <name>"); ``importance`` overrides the declared default. Safe to
        call from any thread; returns at once (the kernel fetches notices, rate-limited and
        deduplicated).
        """
        return self.notices.post(name, data, message=message, importance=importance)


BackendT = TypeVar("BackendT", bound=DeviceBackend, default=Any)
"""A driver's backend class: what its factories build and its server and ``safe_stop`` receive."""
BackendFactory = Callable[[DeviceContext[Any]], DeviceBackend]
ServerFactory = Callable[[DeviceContext[Any], Any], FastMCP]
SafeStop = Callable[[Any], Awaitable[None]]


async def no_safe_stop(backend: Any) -> None:
    """A ``safe_stop`` for devices whose emergency stop has nothing to do."""


class DemoInstance(BaseModel):
    """An instance this driver contributes to the built-in demo world (no config file)."""

    model_config = ConfigDict(extra="forbid")

    description: str
    settings: dict[str, Any] = Field(default_factory=dict)
    sim: dict[str, Any] = Field(default_factory=dict)
    aliases: list[str] = Field(default_factory=list)
    area: str | None = None


class DriverSpec(BaseModel, Generic[BackendT, SettingsT]):
    """The declaration a driver plugin hands to ``register`` in :func:`register_drivers`.

    Generic in the driver's backend and settings classes, so a type checker sees that ``server``
    and ``safe_stop`` receive what ``backends`` build, and that every factory's context carries
    ``settings`` of the class the spec declares (``DriverSpec[TapoBackend, TapoSettings]``;
    ``DriverSpec(...)`` infers both). A plain ``DriverSpec`` annotation means any driver.
    """

    model_config = ConfigDict(arbitrary_types_allowed=True, frozen=True)

    name: str
    """Driver name, as written in ``rosaos.toml``: lowercase letters, digits and underscores."""
    title: str
    """Human title, e.g. ``TP-Link Tapo smart bulb``."""
    description: str
    """What the device can do. The kernel reads it when choosing devices for a task."""
    concurrency: Concurrency
    """``exclusive``: one live process at a time. ``shared``: any number. Enforced by leases."""
    always_attached: bool = False
    """Granted to every process without being asked. True only for the user-interface device."""
    prompt: str
    """The device prompt appended to a process agent's system prompt when it holds the device."""
    attached_tools: tuple[str, ...] = ()
    """For an always-attached driver: the tools a process gets when the kernel granted the device
    only because it is always attached (how to speak to the user). Empty: all of them."""
    attached_prompt: str | None = None
    """The device prompt that goes with :attr:`attached_tools` (short: those tools only)."""
    attached_pattern: str | None = None
    """For an always-attached driver: a case-insensitive regular expression of the words by which
    a task asks for what :attr:`attached_tools` do ("say", "tell", "greet"). When set, a process
    the kernel did not grant the device to gets it only if its task matches: a light switch's
    report is told to the user anyway, and the speaking tools, their prompt and the device prefix
    on every tool name cost a local model about a fifth of the request. None: every process."""
    on_request_tools: tuple[str, ...] = ()
    """Tools a process model is offered only when its task asks for them: the task names one, or
    matches :attr:`on_request_pattern` (:mod:`rosaos.processes.tool_offer`). For expert tools most
    tasks never use: ROS's topic, service, parameter, action and node tools are 25 of its 40
    schemas, 13 KB on every model request of a drive or a search. The offline plan runner may
    call any tool."""
    on_request_pattern: str | None = None
    """Case-insensitive regular expression of the words by which a task asks for :attr:`on_request_tools`."""
    settings: type[SettingsT] = DeviceSettings  # type: ignore[assignment]  # SettingsT defaults to it
    """The settings class of one instance; every context the factories get carries one."""
    server: Callable[[DeviceContext[SettingsT], BackendT], FastMCP]
    """Builds the instance's FastMCP server from its context and its started backend."""
    backends: Mapping[BackendName, Callable[[DeviceContext[SettingsT]], BackendT]]
    intents: Path | None = None
    """Optional hassil-format ``intents.yaml`` mapping sentence templates to tool calls."""
    safe_stop: Callable[[BackendT], Awaitable[None]] = no_safe_stop
    """Awaitable called with the backend on an emergency stop: stop motion, cancel goals."""
    halts: tuple[Halt, ...] = ()
    """What ``safe_stop`` ends on this device, of what a person's "stop" is about: ``motion`` (a
    robot), ``speech``, ``sound`` (music). A bare "stop" ends what moves first, then what speaks,
    then what plays (:mod:`rosaos.kernel.stopping`); () for a device with nothing to halt (a bulb)."""
    confirm_on_real: bool = False
    """Ask a person before destructive tools of a ``real`` instance unless config says otherwise."""
    demo: Mapping[str, DemoInstance] = Field(default_factory=dict)
    """Instances this driver adds to the demo world; defaults to one instance named after it."""
    implemented: bool = True
    """False for a placeholder driver: listed, never served. Not an error."""
    notices: Mapping[str, NoticeSpec] = Field(default_factory=dict)
    """The notices this driver may post with :meth:`DeviceContext.notify`, by name
    (``battery_low``, ``docked``, ``person_seen``). The conformance kit validates them."""
    own_process: bool = False
    """Serve each instance in a host process of its own. ``rosaos up`` otherwise hosts every
    simulated instance of the drivers that do not ask for it in one shared process. Set it when a
    backend runs native code *in the host's own process* whose crash must not take other devices
    along. A daemon the backend starts as a child process (the Reachy's MuJoCo) does not need it;
    blocking SDK calls belong in threads (``asyncio.to_thread``) wherever the device is served."""
    background_start: bool = False
    """``rosaos up`` does not wait for this device: it says "rosaOS is up" while the device is still
    ``starting`` (a physics simulator that boots for seconds), and grants it once it answers. A
    simulated instance joins the running shared host after the others serve."""
    login: Callable[[DeviceContext[SettingsT]], int] | None = None
    """Interactive account login for ``rosaos devices login NAME`` (cloud services such as Spotify):
    called with the instance's context, talks to the user on stdin/stdout, keeps what it obtains
    under ``ctx.data_dir / "drivers" / <driver>``, and returns the exit code. None: no login needed."""
    card: Card | None = None
    """How the web page draws an instance's state (:mod:`rosaos.cards`); None: a plain key list."""

    @field_validator("name")
    @classmethod
    def _valid_name(cls, value: str) -> str:
        if not DRIVER_NAME.match(value):
            raise ValueError(f"driver name {value!r} must match {DRIVER_NAME.pattern}")
        return value

    @field_validator("prompt", "title", "description")
    @classmethod
    def _not_blank(cls, value: str) -> str:
        if not value.strip():
            raise ValueError("must not be empty")
        return value

    @model_validator(mode="after")
    def _needs_sim(self) -> Self:
        if "sim" not in self.backends:
            raise ValueError(f"driver {self.name!r} declares no 'sim' backend; every driver must have one")
        if self.intents is not None and not self.intents.is_file():
            raise ValueError(f"intents file {self.intents} does not exist")
        return self

    def demo_instances(self) -> dict[str, DemoInstance]:
        """The instances this driver contributes to the demo world."""
        if self.demo:
            return dict(self.demo)
        return {self.name: DemoInstance(description=self.description)}


def read_packaged_text(package_file: str, name: str) -> str:
    """Read a text file that ships next to ``package_file`` (pass ``__file__``)."""
    return (Path(package_file).parent / name).read_text(encoding="utf-8")


# --- tool annotations --------------------------------------------------------------------------
# Every device tool declares the MCP hints (the conformance kit checks): clients assume the worst
# otherwise. These are the combinations drivers use; pass one as ``@mcp.tool(annotations=...)``,
# or ``READ_ONLY.model_copy(update={...})`` for a variation.

READ_ONLY = ToolAnnotations(readOnlyHint=True, destructiveHint=False, idempotentHint=True)
"""Reads the device and changes nothing (``get_state``, a camera picture)."""
SETS = ToolAnnotations(readOnlyHint=False, destructiveHint=False, idempotentHint=True)
"""Sets a value: doing it twice is doing it once (``turn_on``, ``set_brightness``, ``safe_stop``)."""
CHANGES = ToolAnnotations(readOnlyHint=False, destructiveHint=False, idempotentHint=False)
"""A change relative to now, or a new event each time (``toggle``, ``next_track``, ``speak``)."""
MOVES = ToolAnnotations(readOnlyHint=False, destructiveHint=True, idempotentHint=False)
"""A robot moves, or anything may happen (raw publishes, service calls, goals)."""
DELETES = ToolAnnotations(readOnlyHint=False, destructiveHint=True, idempotentHint=True)
"""Removes what was stored (forgetting a face); doing it twice is doing it once."""
