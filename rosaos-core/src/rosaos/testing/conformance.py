"""The driver conformance suite: subclass :class:`DriverConformance` and name your driver.

::

    from rosaos.testing import DriverConformance

    class TestMyDriver(DriverConformance):
        driver = "tapo"

Every check is one test. Checks that do not apply skip with the reason (no bounded argument, no
intents file, a placeholder driver); ``exempt`` skips a named check with your reason, like a
quality-scale exemption. The device under test is served exactly as ``rosaos up`` serves it: the
``sim`` backend, over streamable HTTP on loopback, behind a bearer token.

Fixtures for your own behaviour tests in the same class: ``fresh_device`` (a new server in the
initial sim state, per test) and ``shared_device`` (one server per class; do not change its state).
"""

from __future__ import annotations

import asyncio
import re
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any, ClassVar

import httpx
import mcp_types
import pytest

from rosaos.cards import card_keys_missing
from rosaos.config import DeviceConfig
from rosaos.devices.world import DeviceInstance
from rosaos.drivers import DriverSpec
from rosaos.intents.grammar.intents_file import IntentsFile, IntentsFileError, load_intents_file
from rosaos.notices.notice_board import NoticeBatch, check_notice_specs
from rosaos.notices.notice_watcher import notices_url
from rosaos.plugins import DriverInfo, DriverRegistry
from rosaos.testing.device_runner import (
    RunningDevice,
    build_instance,
    load_all_drivers,
    raw_tool_call,
    run_device,
)
from rosaos.testing.tool_checks import (
    OutOfRangeCall,
    control_problems,
    missing_annotations,
    missing_descriptions,
    odd_number_calls,
    out_of_range_candidates,
    result_object,
    result_text,
    untyped_arguments,
)

NOT_IMPLEMENTED = "driver not implemented yet"
ODD_CALL_TIMEOUT = 10.0
"""Seconds a call with a tiny (in-bounds) number may take before the kit calls it unbounded."""


class DriverConformance:
    """What every rosaOS driver must do. Subclass it as ``Test<Something>`` and set :attr:`driver`."""

    driver: ClassVar[str]
    """The driver name, as registered by the plugin and written in ``rosaos.toml``."""
    instance: ClassVar[str | None] = None
    """Demo instance to serve; default: the driver's first demo instance."""
    settings: ClassVar[Mapping[str, Any] | None] = None
    """Instance settings; default: the demo instance's settings."""
    sim_state: ClassVar[Mapping[str, Any] | None] = None
    """Initial sim state; ``get_state`` must echo every key. Default: the demo instance's ``sim``."""
    implemented: ClassVar[bool | None] = None
    """False skips every check that needs a running server. Default: the spec's ``implemented``."""
    out_of_range_call: ClassVar[tuple[str, dict[str, Any]] | None] = None
    """A call that must be refused, e.g. ``("set_brightness", {"brightness": 101})``.
    Default: the first numeric argument with a ``maximum`` in its schema, called with maximum + 1."""
    exempt: ClassVar[Mapping[str, str]] = {}
    """Checks that do not apply to this driver: ``{"test_name": "why"}``."""
    plugin_modules: ClassVar[Mapping[str, ModuleType]] = {}
    """Plugin modules to register directly, as if installed (a driver that is not pip-installed)."""

    # Fixtures

    @pytest.fixture(autouse=True)
    def _exemptions(self, request: pytest.FixtureRequest) -> None:
        reason = self.exempt.get(request.function.__name__)
        if reason:
            pytest.skip(f"exempt: {reason}")

    @pytest.fixture(scope="class")
    @classmethod  # pytest 9 wants class-scoped fixtures bound to the class
    def rosaos_registry(cls) -> DriverRegistry:
        """Every installed driver plugin (plus :attr:`plugin_modules`)."""
        return load_all_drivers(cls.plugin_modules)

    @pytest.fixture(scope="class")
    @classmethod
    def rosaos_driver(cls, rosaos_registry: DriverRegistry) -> DriverInfo:
        """The driver under test; fails with the reason if it did not load."""
        info = rosaos_registry.drivers.get(cls.driver)
        if info is None:
            pytest.fail(_not_loaded_message(cls.driver, rosaos_registry), pytrace=False)
        return info

    @pytest.fixture(scope="class")
    @classmethod
    def rosaos_instance(cls, rosaos_driver: DriverInfo) -> DeviceInstance:
        """The ``sim`` instance the suite serves."""
        demo = rosaos_driver.spec.demo_instances()
        name = cls.instance or next(iter(demo))
        default = demo.get(name)
        try:
            return build_instance(
                rosaos_driver,
                name,
                description=default.description if default else None,
                settings=cls.settings if cls.settings is not None else (default.settings if default else {}),
                sim=cls.sim_state if cls.sim_state is not None else (default.sim if default else {}),
            )
        except ValueError as error:
            pytest.fail(f"the settings do not validate:\n{error}", pytrace=False)

    @pytest.fixture(scope="class")
    @classmethod
    def started_device(
        cls,
        rosaos_driver: DriverInfo,
        rosaos_instance: DeviceInstance,
        tmp_path_factory: pytest.TempPathFactory,
    ) -> Iterator[tuple[RunningDevice, dict[str, Any] | str]]:
        """The class's one server, and its ``get_state`` read as it started, before any test ran
        (or why it could not be read: only :meth:`test_sim_state_is_honoured` fails on that)."""
        cls._skip_unless_implemented(rosaos_driver.spec)
        with run_device(rosaos_instance, tmp_path_factory.mktemp("rosaos-data")) as device:
            yield device, asyncio.run(_get_state(device))

    @pytest.fixture(scope="class")
    @classmethod
    def shared_device(cls, started_device: tuple[RunningDevice, dict[str, Any] | str]) -> RunningDevice:
        """One server for the whole class. Tests using it must not change the device state."""
        return started_device[0]

    @pytest.fixture(scope="class")
    @classmethod
    def shared_tools(cls, shared_device: RunningDevice) -> list[mcp_types.Tool]:
        """The tools the shared server lists over HTTP, listed once (the listing does not change)."""
        return asyncio.run(_list_tools(shared_device))

    @pytest.fixture
    def fresh_device(
        self, rosaos_driver: DriverInfo, rosaos_instance: DeviceInstance, tmp_path: Path
    ) -> Iterator[RunningDevice]:
        """A new server in the initial sim state, for a test that changes the device."""
        self._skip_unless_implemented(rosaos_driver.spec)
        with run_device(rosaos_instance, tmp_path / "rosaos-data") as device:
            yield device

    @classmethod
    def _skip_unless_implemented(cls, spec: DriverSpec) -> None:
        implemented = spec.implemented if cls.implemented is None else cls.implemented
        if not implemented:
            pytest.skip(f"{NOT_IMPLEMENTED}: {spec.name} is a placeholder")

    # The declaration

    def test_entry_point_resolves(self, rosaos_registry: DriverRegistry) -> None:
        """The plugin loads through the ``rosaos.drivers`` entry point and its spec validates."""
        assert self.driver in rosaos_registry.drivers, _not_loaded_message(self.driver, rosaos_registry)
        info = rosaos_registry.drivers[self.driver]
        broken = [b for b in rosaos_registry.broken if b.plugin in (self.driver, info.plugin)]
        assert not broken, f"{info.package} has broken plugins: {broken}"

    def test_prompt_is_not_empty(self, rosaos_driver: DriverInfo) -> None:
        """The device prompt tells a process agent how to use the device."""
        assert rosaos_driver.spec.prompt.strip(), "the device prompt is empty; write prompt.md"

    def test_concurrency_is_declared(self, rosaos_driver: DriverInfo) -> None:
        """The spec says whether one process or many may hold an instance."""
        assert rosaos_driver.spec.concurrency in ("exclusive", "shared")

    def test_sim_backend_exists(self, rosaos_driver: DriverInfo) -> None:
        """Every driver runs with no hardware: a ``sim`` backend factory is declared."""
        assert callable(rosaos_driver.spec.backends.get("sim")), "declare backends={'sim': ...}"

    def test_settings_do_not_shadow_instance_keys(self, rosaos_driver: DriverInfo) -> None:
        """No driver setting is named like a key rosaOS itself reads from ``[devices.NAME]``."""
        reserved = set(DeviceConfig.model_fields)
        shadowed = sorted(reserved & set(rosaos_driver.spec.settings.model_fields))
        assert not shadowed, (
            f"settings {', '.join(shadowed)} can never be set: rosaOS reads [devices.NAME] "
            f"{', '.join(shadowed)} itself (reserved: {', '.join(sorted(reserved))}); rename them, e.g. device_port"
        )

    def test_intents_file_parses(self, rosaos_driver: DriverInfo) -> None:
        """The intents file parses with hassil, and every intent names a tool."""
        intents = _intents_file(rosaos_driver.spec)
        assert intents.actions or intents.capabilities, (
            f"{intents.path}: declares no intent and no capabilities"
        )

    def test_declared_notices_validate(self, rosaos_driver: DriverInfo) -> None:
        """Every notice in ``DriverSpec.notices`` has a valid name, a schema, and an example that validates."""
        problems = check_notice_specs(rosaos_driver.spec.notices)
        assert not problems, "; ".join(problems)

    @pytest.mark.asyncio
    async def test_notices_are_served_behind_the_token(self, shared_device: RunningDevice) -> None:
        """``GET /notices`` (how the kernel reads ``ctx.notify``) answers with the token, 401 without."""
        url = notices_url(shared_device.url)
        async with httpx.AsyncClient(timeout=10) as http:
            anonymous = await http.get(url)
            answer = await http.get(url, headers={"Authorization": f"Bearer {shared_device.token}"})
        assert anonymous.status_code == 401
        assert answer.status_code == 200, answer.text
        batch = NoticeBatch.model_validate_json(answer.content)
        undeclared = {n.name for n in batch.notices} - set(shared_device.instance.spec.notices)
        assert not undeclared, f"posted notices not declared in DriverSpec.notices: {sorted(undeclared)}"

    # The server, over HTTP

    def test_sim_backend_says_it_is_simulated(self, shared_device: RunningDevice) -> None:
        """The ``sim`` backend sets ``simulated = True``, so ``rosaos devices list`` shows it."""
        assert shared_device.simulated, "set simulated = True on the sim backend"

    def test_server_lists_its_tools(self, shared_tools: list[mcp_types.Tool]) -> None:
        """The server starts over HTTP and lists ``get_state`` and ``safe_stop`` among its tools."""
        names = {tool.name for tool in shared_tools}
        assert {"get_state", "safe_stop"} <= names, f"tools listed: {sorted(names)}"

    @pytest.mark.asyncio  # explicit, so the kit also runs under asyncio_mode=strict
    async def test_request_without_token_is_refused(self, shared_device: RunningDevice) -> None:
        """Without the bearer token, or with a wrong one, the server answers 401."""
        ping = {"jsonrpc": "2.0", "id": 1, "method": "ping"}
        async with httpx.AsyncClient(timeout=10) as http:
            anonymous = await http.post(shared_device.url, json=ping)
            wrong = await http.post(shared_device.url, json=ping, headers={"Authorization": "Bearer wrong"})
        assert (anonymous.status_code, wrong.status_code) == (401, 401)

    def test_every_tool_has_a_description(self, shared_tools: list[mcp_types.Tool]) -> None:
        """The model picks tools by their description."""
        problems = missing_descriptions(shared_tools)
        assert not problems, "\n".join(problems)

    def test_prompt_calls_only_tools_the_server_has(
        self, rosaos_driver: DriverInfo, shared_tools: list[mcp_types.Tool]
    ) -> None:
        """``prompt.md`` names no tool the server lacks: a process agent is sent the tools as schemas
        from the server's own metadata, and the prose must agree with them."""
        names = {tool.name for tool in shared_tools}
        called = set(re.findall(r"`([a-z_][a-z0-9_]*)\(", rosaos_driver.spec.prompt))
        unknown = sorted(called - names)
        assert not unknown, (
            f"prompt.md calls {', '.join(unknown)}, which the server does not have "
            f"(its tools: {', '.join(sorted(names))}); rename them in prompt.md or add the tools"
        )

    def test_every_tool_argument_is_typed(self, shared_tools: list[mcp_types.Tool]) -> None:
        """Every argument has a JSON-schema type, so the model knows what to send."""
        problems = untyped_arguments(shared_tools)
        assert not problems, "\n".join(problems)

    def test_every_tool_has_explicit_annotations(self, shared_tools: list[mcp_types.Tool]) -> None:
        """``readOnlyHint`` and ``destructiveHint`` are set on every tool, not left to defaults."""
        problems = missing_annotations(shared_tools)
        assert not problems, "\n".join(problems)

    def test_get_state_is_read_only(self, shared_tools: list[mcp_types.Tool]) -> None:
        """``get_state`` is annotated ``readOnlyHint: true``."""
        tools = {tool.name: tool for tool in shared_tools}
        annotations = tools["get_state"].annotations
        assert annotations is not None, "get_state has no annotations; set readOnlyHint: True"
        assert annotations.read_only_hint is True, "annotate get_state with readOnlyHint: True"

    @pytest.mark.asyncio
    async def test_get_state_returns_a_json_object(self, shared_device: RunningDevice) -> None:
        """``get_state`` returns the device state as one JSON object."""
        async with shared_device.client() as client:
            result = await client.call_tool_mcp("get_state", {})
        assert not result.is_error, result_text(result)
        assert isinstance(result_object(result), dict)

    @pytest.mark.asyncio
    async def test_card_reads_keys_of_get_state(
        self, rosaos_driver: DriverInfo, shared_device: RunningDevice
    ) -> None:
        """The web card the driver declares (``DriverSpec.card``) reads keys ``get_state`` has."""
        card = rosaos_driver.spec.card
        if card is None:
            return  # no card declared: the page lists the state keys as they are
        async with shared_device.client() as client:
            state = result_object(await client.call_tool_mcp("get_state", {}))
        missing = card_keys_missing(card, state)
        assert not missing, (
            f"the card of driver {rosaos_driver.spec.name!r} reads {', '.join(missing)}, "
            f"which get_state does not return (it returns: {', '.join(state)})"
        )

    @pytest.mark.asyncio
    async def test_out_of_range_argument_is_a_tool_error(
        self, shared_device: RunningDevice, shared_tools: list[mcp_types.Tool]
    ) -> None:
        """An out-of-range argument is refused with a message naming it; the server keeps answering."""
        call = self._out_of_range(shared_tools)
        async with shared_device.client() as client:
            result = await client.call_tool_mcp(call.tool, call.args)
            after = await client.call_tool_mcp("get_state", {})
        text = result_text(result)
        assert result.is_error, f"{call.tool}({call.args}) was accepted; bound it, e.g. Field(le=...)"
        assert "Traceback" not in text, f"{call.tool}({call.args}) crashed instead of refusing: {text}"
        assert any(name.lower() in text.lower() for name in call.named), (
            f"{call.tool}({call.args}) failed with a message that does not name {' or '.join(call.named)}: {text!r}"
        )
        assert not after.is_error, f"get_state failed after the refused call: {result_text(after)}"

    def test_card_controls_call_real_tools_with_valid_arguments(
        self, rosaos_driver: DriverInfo, shared_tools: list[mcp_types.Tool]
    ) -> None:
        """Every control on the card (``Card.of(..., controls=[...])``) calls a tool the server has,
        with arguments its input schema accepts: each end of a slider, each option of a choice."""
        card = rosaos_driver.spec.card
        if card is None or not card.controls:
            return  # no controls declared: the card only shows state
        problems = control_problems(card.controls, shared_tools)
        assert not problems, f"card controls of driver {rosaos_driver.spec.name!r}:\n" + "\n".join(problems)

    @pytest.mark.asyncio
    async def test_odd_numbers_are_refused_or_answered(
        self, fresh_device: RunningDevice, shared_tools: list[mcp_types.Tool]
    ) -> None:
        """NaN and ±Inf are refused on every number of every tool; 0 and 1e-9 are refused where the
        bounds exclude them, and otherwise the call still comes back (no move that lasts for ever)."""
        problems = []
        for call in odd_number_calls(shared_tools):
            shown = f"{call.tool}({call.name}={call.value!r})"
            try:
                result = await raw_tool_call(fresh_device, call.tool, call.args, ODD_CALL_TIMEOUT)
            except TimeoutError:
                problems.append(
                    f"{shown} did not return within {ODD_CALL_TIMEOUT:g} s; give it a practical bound "
                    "(e.g. Field(ge=0.02) for a speed)"
                )
                await raw_tool_call(fresh_device, "safe_stop", {}, ODD_CALL_TIMEOUT)
                continue
            text = " ".join(str(block.get("text", "")) for block in result.get("content") or [])
            if call.must_refuse and not result.get("isError"):
                problems.append(f"{shown} was accepted; numbers must be finite and within their bounds")
            if "Traceback" in text:
                problems.append(f"{shown} crashed instead of refusing: {text[:200]}")
        await raw_tool_call(fresh_device, "safe_stop", {}, ODD_CALL_TIMEOUT)
        assert not problems, "\n".join(problems)

    def test_intents_name_existing_tools(
        self, rosaos_driver: DriverInfo, shared_tools: list[mcp_types.Tool]
    ) -> None:
        """Every intent and every capability calls a tool the server has, with arguments that tool
        takes; a question (an intent with ``answer`` or ``reply``) calls a read-only tool, so asking
        moves nothing."""
        intents = _intents_file(rosaos_driver.spec)
        tools = {tool.name: tool for tool in shared_tools}
        problems = []
        for intent, action in intents.actions.items():
            tool = tools.get(action.tool)
            if tool is None:
                problems.append(f"{intent}: no tool {action.tool!r}; tools: {', '.join(sorted(tools))}")
                continue
            accepted = set(tool.input_schema.get("properties") or {})
            required = set(tool.input_schema.get("required") or [])
            if unknown := sorted(set(action.args) - accepted):
                problems.append(f"{intent}: {action.tool} takes no argument {', '.join(unknown)}")
            if missing := sorted(required - set(action.args)):
                problems.append(f"{intent}: {action.tool} needs {', '.join(missing)}; add them under args")
            read_only = tool.annotations is not None and tool.annotations.read_only_hint is True
            if action.is_question and not read_only:
                problems.append(
                    f"{intent}: a question (answer/reply) must call a read-only tool such as get_state; "
                    f"{action.tool} is not annotated readOnlyHint=true"
                )
        for capability in intents.capabilities.can if intents.capabilities else ():
            where = f"capabilities: {capability.does} ({capability.tool})"
            tool = tools.get(capability.tool)
            if tool is None:
                problems.append(f"{where}: no tool {capability.tool!r}; tools: {', '.join(sorted(tools))}")
                continue
            accepted = set(tool.input_schema.get("properties") or {})
            required = set(tool.input_schema.get("required") or [])
            given = set(capability.args) | set(capability.fixed)
            if unknown := sorted(given - accepted):
                problems.append(f"{where}: {capability.tool} takes no argument {', '.join(unknown)}")
            if missing := sorted(required - given):
                problems.append(
                    f"{where}: {capability.tool} needs {', '.join(missing)}; give their meaning under args"
                )
        assert not problems, f"{intents.path}:\n" + "\n".join(problems)

    @pytest.mark.asyncio
    async def test_safe_stop_runs(self, shared_device: RunningDevice) -> None:
        """The ``safe_stop`` tool runs the driver's emergency stop without error."""
        async with shared_device.client() as client:
            result = await client.call_tool_mcp("safe_stop", {})
        assert not result.is_error, result_text(result)

    def test_sim_state_is_honoured(self, started_device: tuple[RunningDevice, dict[str, Any] | str]) -> None:
        """The sim backend starts in the state the instance's ``sim`` table gives (read from the
        shared server as it started, before any test could change it: no second server)."""
        device, state = started_device
        expected = device.instance.sim
        if not expected:
            pytest.skip("no initial sim state to check; set sim_state on the test class")
        assert isinstance(state, dict), f"get_state did not answer as the server started: {state}"
        differences = {
            key: state.get(key, "<missing>") for key, value in expected.items() if state.get(key) != value
        }
        assert not differences, f"get_state disagrees with sim={dict(expected)}: got {differences}"

    # Helpers

    def _out_of_range(self, tools: list[mcp_types.Tool]) -> OutOfRangeCall:
        if self.out_of_range_call is not None:
            tool, args = self.out_of_range_call
            return OutOfRangeCall(tool, dict(args), tuple(args))
        candidates = out_of_range_candidates(tools)
        if not candidates:
            pytest.skip("no tool has a numeric argument with a maximum; set out_of_range_call to test one")
        return candidates[0]


async def _get_state(device: RunningDevice) -> dict[str, Any] | str:
    try:
        async with device.client() as client:
            return result_object(await client.call_tool_mcp("get_state", {}))
    except Exception as error:  # reported by the one check that needs it, not by every test
        return f"{type(error).__name__}: {error}"


async def _list_tools(device: RunningDevice) -> list[mcp_types.Tool]:
    async with device.client() as client:
        return await client.list_tools()


def _intents_file(spec: DriverSpec) -> IntentsFile:
    if spec.intents is None:
        pytest.skip("the driver ships no intents file")
    try:
        return load_intents_file(spec.intents)
    except IntentsFileError as error:
        pytest.fail(str(error), pytrace=False)


def _not_loaded_message(driver: str, registry: DriverRegistry) -> str:
    lines = [f"driver {driver!r} is not installed; installed: {', '.join(registry.names) or 'none'}"]
    lines += [f"broken plugin {b.plugin} ({b.package}): {b.error}" for b in registry.broken]
    lines.append('check the [project.entry-points."rosaos.drivers"] table and pip install -e the package')
    return "\n".join(lines)
