"""open_sim_device (rosaos.testing.sim_device): a driver's server on its sim backend, in memory."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import pytest
from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import Field

from rosaos.drivers import DemoInstance, DeviceBackend, DeviceContext, DeviceError, DeviceSettings, DriverSpec
from rosaos.testing import open_sim_device


class LampSettings(DeviceSettings):
    max_level: int = Field(default=100, ge=1, le=100)


BACKENDS: list[LampBackend] = []
"""Every backend built, newest last."""


class LampBackend(DeviceBackend):
    """Records its life cycle, so tests can see it was started and closed."""

    simulated = True

    def __init__(self, ctx: DeviceContext) -> None:
        self.ctx = ctx
        self.level = int(ctx.sim.get("level", 0))
        self.events: list[str] = []
        BACKENDS.append(self)

    async def start(self) -> None:
        if self.ctx.sim.get("broken"):
            raise DeviceError("the lamp does not answer")
        self.events.append("start")

    async def close(self) -> None:
        self.events.append("close")


def build_server(ctx: DeviceContext, backend: LampBackend) -> FastMCP:
    mcp = FastMCP(ctx.instance)

    @mcp.tool
    async def get_state() -> dict[str, Any]:
        """Read the lamp."""
        return {"level": backend.level}

    @mcp.tool
    async def set_level(level: Annotated[int, Field(ge=0, le=100)]) -> dict[str, Any]:
        """Set the level."""
        backend.level = level
        return {"level": level}

    return mcp


SPEC = DriverSpec(
    name="lamp",
    title="Lamp",
    description="A lamp.",
    concurrency="exclusive",
    prompt="You control a lamp.",
    settings=LampSettings,
    server=build_server,
    backends={"sim": LampBackend},
    demo={
        "desk_lamp": DemoInstance(description="Lamp on the desk", sim={"level": 20}),
        "floor_lamp": DemoInstance(description="Floor lamp", settings={"max_level": 80}, sim={"level": 60}),
    },
)


async def test_call_returns_the_structured_result_and_state_reads_get_state() -> None:
    async with open_sim_device(SPEC) as lamp:
        assert await lamp.call("set_level", level=30) == {"level": 30}
        assert await lamp.state() == {"level": 30}


async def test_error_returns_the_text_of_a_refused_call() -> None:
    async with open_sim_device(SPEC) as lamp:
        assert "level" in await lamp.error("set_level", level=101)


async def test_error_fails_when_the_call_succeeds() -> None:
    async with open_sim_device(SPEC) as lamp:
        with pytest.raises(AssertionError, match="should have failed"):
            await lamp.error("set_level", level=50)


async def test_call_raises_the_tool_error() -> None:
    async with open_sim_device(SPEC) as lamp:
        with pytest.raises(ToolError):
            await lamp.call("set_level", level=-1)


async def test_the_first_demo_instance_is_the_default() -> None:
    async with open_sim_device(SPEC) as lamp:
        assert (lamp.context.instance, lamp.context.description) == ("desk_lamp", "Lamp on the desk")
        assert await lamp.state() == {"level": 20}


async def test_a_named_demo_instance_brings_its_settings_and_sim_table() -> None:
    async with open_sim_device(SPEC, "floor_lamp") as lamp:
        assert isinstance(lamp.context.settings, LampSettings)
        assert lamp.context.settings.max_level == 80
        assert await lamp.state() == {"level": 60}


async def test_a_given_sim_table_replaces_the_demo_one() -> None:
    async with open_sim_device(SPEC, "floor_lamp", sim={}) as lamp:
        assert await lamp.state() == {"level": 0}


async def test_an_instance_that_is_not_in_the_demo_gets_the_driver_description() -> None:
    async with open_sim_device(SPEC, "attic_lamp", sim={"level": 5}) as lamp:
        assert (lamp.context.instance, lamp.context.description) == ("attic_lamp", "A lamp.")
        assert await lamp.state() == {"level": 5}


async def test_bad_settings_are_refused_with_the_setting_named() -> None:
    with pytest.raises(ValueError, match=r"devices\.desk_lamp.*max_level"):
        async with open_sim_device(SPEC, settings={"max_level": 0}):
            pass


async def test_the_backend_is_started_then_closed() -> None:
    async with open_sim_device(SPEC) as lamp:
        assert lamp.backend.simulated
        assert BACKENDS[-1].events == ["start"]
    assert BACKENDS[-1].events == ["start", "close"]


async def test_the_backend_is_closed_after_a_failed_start() -> None:
    with pytest.raises(DeviceError, match="does not answer"):
        async with open_sim_device(SPEC, sim={"broken": True}):
            pass
    assert BACKENDS[-1].events == ["close"]


async def test_the_default_data_dir_is_a_temporary_folder_removed_on_exit() -> None:
    async with open_sim_device(SPEC) as lamp:
        data_dir = lamp.context.data_dir
        assert data_dir.is_dir()
    assert not data_dir.exists()


async def test_a_given_data_dir_is_used(tmp_path: Path) -> None:
    async with open_sim_device(SPEC, data_dir=tmp_path) as lamp:
        assert lamp.context.data_dir == tmp_path
