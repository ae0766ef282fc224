"""The conformance kit (rosaos.testing) passes a good driver and fails each defect of a sloppy one.

A scratch test module holds a fake driver and one ``DriverConformance`` subclass per case; pytest
runs it once, in a subprocess, in a directory with no pytest configuration (so pytest-asyncio's
strict mode, what a third-party package gets by default). Each test below reads its case's
outcomes from the JUnit XML report.
"""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from types import SimpleNamespace

import pytest

from rosaos.testing import pytest_plugin

DRIVER = '''
import sys
from pathlib import Path
from typing import Annotated, Any

from fastmcp import FastMCP
from pydantic import BaseModel, Field

from rosaos import hookimpl
from rosaos.cards import Card, flag, gauge
from rosaos.drivers import DeviceBackend, DeviceError, DeviceSettings, DemoInstance, DriverSpec, NoticeSpec
from rosaos.testing import DriverConformance


class Backend(DeviceBackend):
    simulated = True

    def __init__(self, ctx):
        self.state = {key: ctx.sim.get(key, value) for key, value in {"on": False, "level": 50}.items()}


def good_server(ctx, backend):
    mcp = FastMCP(ctx.instance)

    @mcp.tool(annotations={"readOnlyHint": True, "destructiveHint": False})
    async def get_state() -> dict[str, Any]:
        """Read the device."""
        return backend.state

    @mcp.tool(annotations={"readOnlyHint": False, "destructiveHint": False})
    async def set_level(level: Annotated[int, Field(ge=0, le=100)]) -> dict[str, Any]:
        """Set the level."""
        backend.state["level"] = level
        return backend.state

    return mcp


def sloppy_server(ctx, backend):
    mcp = FastMCP(ctx.instance)

    @mcp.tool
    async def get_state() -> str:
        return "fine"

    @mcp.tool(annotations={"readOnlyHint": False, "destructiveHint": True})
    async def poke(anything) -> str:
        """Poke it."""
        return "poked"

    @mcp.tool(annotations={"readOnlyHint": False, "destructiveHint": False})
    async def set_level(level: Annotated[int, Field(json_schema_extra={"maximum": 100})]) -> str:
        """Set the level (the schema says at most 100; nothing enforces it)."""
        return "set"

    return mcp


class Heat(BaseModel):
    celsius: float


BROKEN_NOTICES = {"overheated": NoticeSpec(description="Too hot", data=Heat, example={"celsius": "very"})}


def spec(**overrides):
    fields = dict(
        name="fake", title="Fake", description="A fake device.", concurrency="exclusive",
        prompt="You control a fake device.", server=good_server, backends={"sim": Backend},
        demo={"fake_one": DemoInstance(description="Fake one", sim={"level": 20})},
        card=Card.of(flag("on"), gauge("level", unit="%")),
    )
    return DriverSpec(**(fields | overrides))


ASKING_INTENTS = Path(__file__).parent / "asking_intents.yaml"
ASKING_INTENTS.write_text(
    "intents:\\n"
    "  Level:\\n"
    "    data: [{sentences: ['what is [the] level']}]\\n"
    "    tool: get_state\\n"
    "    reply: 'Level {level}.'\\n"
    "  LevelUp:\\n"
    "    data: [{sentences: ['is [the] level up']}]\\n"
    "    tool: set_level\\n"
    "    args: {level: 100}\\n"
    "    answer: {when: {level: 100}, 'yes': 'Yes.', 'no': 'No.'}\\n",
    encoding="utf-8",
)


@hookimpl
def register_drivers(register):
    register(spec())
    register(spec(name="sloppy", server=sloppy_server, notices=BROKEN_NOTICES, card=None))
    register(spec(name="placeholder", implemented=False))
    register(spec(name="asks", intents=ASKING_INTENTS))
    register(spec(name="miscarded", card=Card.of(gauge("level"), gauge("brightness"))))


class Kit(DriverConformance):
    driver = "fake"
    plugin_modules = {"fake": sys.modules[__name__]}
'''


CASES = """
class TestGood(Kit):
    pass


class TestSloppy(Kit):
    driver = "sloppy"
    sim_state = {}


class TestExplicitOutOfRange(Kit):
    out_of_range_call = ("set_level", {"level": -1})


class TestIgnoresSim(Kit):
    sim_state = {"level": 20, "colour": "red"}


class TestPlaceholder(Kit):
    driver = "placeholder"


class TestExempt(Kit):
    exempt = {"test_safe_stop_runs": "the device has no motion to stop"}


class TestMissing(Kit):
    driver = "fridge"


class TestAsksWithATool(Kit):
    driver = "asks"


class TestMiscarded(Kit):
    driver = "miscarded"
"""


@dataclass(frozen=True)
class Outcome:
    status: str
    """passed, failed, skipped or error."""
    message: str


Report = dict[str, dict[str, Outcome]]


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Report:
    """Run the scratch suite once; outcomes by test class, then by test name."""
    folder = tmp_path_factory.mktemp("kit")
    (folder / "test_driver.py").write_text(DRIVER + CASES, encoding="utf-8")
    xml = folder / "report.xml"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-p",
            "no:cacheprovider",
            f"--junitxml={xml}",
            "-q",
            "-o",
            "asyncio_default_fixture_loop_scope=function",
            "test_driver.py",
        ],
        cwd=folder,
        capture_output=True,
        check=False,
        timeout=240,
    )
    outcomes: Report = {}
    for case in ElementTree.parse(xml).iter("testcase"):
        detail = next(iter(case), None)
        status = "passed" if detail is None else {"failure": "failed"}.get(detail.tag, detail.tag)
        message = "" if detail is None else (detail.get("message", "") + "\n" + (detail.text or ""))
        cls = case.get("classname", "").rsplit(".", 1)[-1]
        outcomes.setdefault(cls, {})[case.get("name", "")] = Outcome(status, message)
    return outcomes


def statuses(report: Report, cls: str) -> dict[str, str]:
    return {name: outcome.status for name, outcome in report[cls].items()}


def not_passed(report: Report, cls: str) -> dict[str, str]:
    return {name: status for name, status in statuses(report, cls).items() if status != "passed"}


INTENTS_SKIPPED = {"test_intents_file_parses": "skipped", "test_intents_name_existing_tools": "skipped"}


def test_a_good_driver_passes_every_check_that_applies(report: Report) -> None:
    assert (
        len(report["TestGood"]) == 24
    )  # every check of the kit, card controls, odd numbers and the prompt's tool names included
    assert not_passed(report, "TestGood") == INTENTS_SKIPPED
    assert "the driver ships no intents file" in report["TestGood"]["test_intents_file_parses"].message


def test_each_defect_of_a_sloppy_driver_fails_its_own_check(report: Report) -> None:
    failed = {name for name, status in statuses(report, "TestSloppy").items() if status == "failed"}
    assert failed == {
        "test_every_tool_has_a_description",
        "test_every_tool_argument_is_typed",
        "test_every_tool_has_explicit_annotations",
        "test_get_state_is_read_only",
        "test_get_state_returns_a_json_object",
        "test_out_of_range_argument_is_a_tool_error",
        "test_declared_notices_validate",
    }


def test_failure_messages_name_the_tool_and_the_fix(report: Report) -> None:
    sloppy = report["TestSloppy"]
    assert "poke(anything): untyped argument" in sloppy["test_every_tool_argument_is_typed"].message
    assert (
        "get_state: no description; write a docstring" in sloppy["test_every_tool_has_a_description"].message
    )
    assert (
        "set_level({'level': 101}) was accepted"
        in sloppy["test_out_of_range_argument_is_a_tool_error"].message
    )


def test_a_notice_whose_example_breaks_its_model_fails(report: Report) -> None:
    message = report["TestSloppy"]["test_declared_notices_validate"].message
    assert "notice 'overheated': its example does not validate" in message


def test_a_question_intent_that_calls_an_acting_tool_fails(report: Report) -> None:
    assert not_passed(report, "TestAsksWithATool") == {"test_intents_name_existing_tools": "failed"}
    message = report["TestAsksWithATool"]["test_intents_name_existing_tools"].message
    assert "LevelUp: a question (answer/reply) must call a read-only tool" in message
    assert "Level:" not in message  # the get_state question is fine


def test_a_card_that_reads_a_key_get_state_lacks_fails(report: Report) -> None:
    assert not_passed(report, "TestMiscarded") == INTENTS_SKIPPED | {
        "test_card_reads_keys_of_get_state": "failed"
    }
    message = report["TestMiscarded"]["test_card_reads_keys_of_get_state"].message
    assert "reads brightness, which get_state does not return (it returns: on, level)" in message


def test_an_explicit_out_of_range_call_is_used(report: Report) -> None:
    assert (
        statuses(report, "TestExplicitOutOfRange")["test_out_of_range_argument_is_a_tool_error"] == "passed"
    )


def test_a_sim_that_ignores_its_initial_state_fails(report: Report) -> None:
    assert not_passed(report, "TestIgnoresSim") == INTENTS_SKIPPED | {"test_sim_state_is_honoured": "failed"}
    assert "'colour': '<missing>'" in report["TestIgnoresSim"]["test_sim_state_is_honoured"].message


def test_a_placeholder_driver_runs_the_declaration_checks_and_skips_the_server_ones(report: Report) -> None:
    placeholder = report["TestPlaceholder"]
    skipped = {name for name, outcome in placeholder.items() if outcome.status == "skipped"}
    assert set(placeholder) - skipped == {
        "test_entry_point_resolves",
        "test_prompt_is_not_empty",
        "test_concurrency_is_declared",
        "test_sim_backend_exists",
        "test_settings_do_not_shadow_instance_keys",
        "test_declared_notices_validate",
    }
    assert (
        "driver not implemented yet: placeholder is a placeholder"
        in placeholder["test_safe_stop_runs"].message
    )


def test_an_exemption_skips_that_check_with_its_reason(report: Report) -> None:
    exempt = report["TestExempt"]["test_safe_stop_runs"]
    assert (exempt.status, "exempt: the device has no motion to stop" in exempt.message) == ("skipped", True)


def test_a_driver_that_is_not_installed_fails_naming_the_installed_ones(report: Report) -> None:
    missing = report["TestMissing"]["test_entry_point_resolves"]
    assert missing.status == "failed"
    assert "driver 'fridge' is not installed; installed: " in missing.message
    assert "fake" in missing.message.split("installed: ")[1]


def test_the_kit_checks_carry_the_marker_and_a_driver_s_own_tests_do_not() -> None:
    from rosaos.testing import DriverConformance

    class TestLamp(DriverConformance):
        driver = "lamp"

        def test_own_behaviour(self) -> None:
            """A driver's own test."""

    def item(name: str) -> SimpleNamespace:
        return SimpleNamespace(
            cls=TestLamp, function=getattr(TestLamp, name), markers=[], add_marker=lambda m: None
        )

    items = [item("test_safe_stop_runs"), item("test_own_behaviour")]
    marked: list[str] = []
    for entry in items:
        entry.add_marker = lambda marker, entry=entry: marked.append(entry.function.__name__)
    pytest_plugin.pytest_collection_modifyitems(items)  # type: ignore[arg-type]
    assert marked == ["test_safe_stop_runs"]
