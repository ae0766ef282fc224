"""DeviceClient: get_state and tool calls over HTTP, and failures that say what to do."""

from __future__ import annotations

import time
from collections.abc import AsyncIterator
from pathlib import Path

import pytest

from rosaos.devices.client import DeviceClient
from rosaos.devices.serve import ServedDevice, open_device, serve_http
from rosaos.drivers import DeviceError

from .devices_support import closed_port_url, drivers_for_tests, world_of

TOKEN = "test-token"


@pytest.fixture
async def served(data_dir: Path) -> AsyncIterator[ServedDevice]:
    world = world_of(drivers_for_tests(), data_dir, lamp={"driver": "tiny", "sim": {"on": True}})
    async with open_device(world.get("lamp"), data_dir) as device, serve_http(device.server, TOKEN) as http:
        yield http


async def test_get_state_returns_the_state_as_a_dict(served: ServedDevice) -> None:
    assert await DeviceClient(served.url, TOKEN).get_state() == {"on": True}


async def test_call_returns_the_tool_result(served: ServedDevice) -> None:
    client = DeviceClient(served.url, TOKEN)
    assert await client.call("switch", {"on": False}) == {"on": False}
    assert await client.get_state() == {"on": False}


async def test_one_session_serves_several_calls(served: ServedDevice) -> None:
    async with DeviceClient(served.url, TOKEN) as client:
        await client.call("switch", {"on": False})
        assert await client.get_state() == {"on": False}


async def test_list_tools_includes_get_state_and_safe_stop(served: ServedDevice) -> None:
    names = {tool.name for tool in await DeviceClient(served.url, TOKEN).list_tools()}
    assert {"get_state", "switch", "safe_stop"} <= names


async def test_a_tool_error_names_the_tool_and_keeps_the_drivers_advice(served: ServedDevice) -> None:
    with pytest.raises(DeviceError, match=r"lamp .*broken failed: .*check that it has power"):
        await DeviceClient(served.url, TOKEN, name="lamp").call("broken")


async def test_a_wrong_token_is_reported_as_refused(served: ServedDevice) -> None:
    with pytest.raises(DeviceError, match="refused the token"):
        await DeviceClient(served.url, "not-the-token").get_state()


async def test_nothing_listening_says_how_to_start_it_and_fails_fast() -> None:
    url = closed_port_url()
    started = time.monotonic()
    with pytest.raises(DeviceError) as caught:
        await DeviceClient(url, TOKEN, timeout=10, name="kitchen_light").get_state()
    assert time.monotonic() - started < 3
    assert str(caught.value) == (
        f"nothing is listening at {url}: is `rosaos up` or `rosaos serve-device kitchen_light` running?"
    )


async def test_a_slow_device_times_out_with_the_limit_in_the_message(served: ServedDevice) -> None:
    with pytest.raises(DeviceError, match=r"did not answer within 0\.5 s"):
        await DeviceClient(served.url, TOKEN, timeout=0.5).call("slow", {"seconds": 5})


async def test_a_url_without_mcp_path_is_explained(served: ServedDevice) -> None:
    with pytest.raises(DeviceError, match="device URLs end in /mcp"):
        await DeviceClient(served.url.removesuffix("/mcp") + "/other", TOKEN).get_state()


async def test_in_process_client_reads_state_without_http(data_dir: Path) -> None:
    world = world_of(drivers_for_tests(), data_dir, lamp={"driver": "tiny"})
    async with open_device(world.get("lamp"), data_dir) as device:
        assert await DeviceClient.in_process(device.server).get_state() == {"on": False}
