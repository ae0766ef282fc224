"""The real backend's failures, each turned into a message that says what to fix.

The network cases run against servers on loopback (nothing listening, a bulb that never answers,
a KLAP bulb owned by another account), so kasa's real transport produces the failure.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import os
import socket
import time
from collections.abc import AsyncIterator
from typing import Any

import pytest
from aiohttp import web
from fastmcp import Client
from kasa import AuthenticationError, Device, KasaException
from kasa import DeviceError as KasaDeviceError
from kasa.protocols import SmartProtocol
from kasa.smart import SmartDevice

from rosaos.drivers import DeviceContext, DeviceError
from rosaos_tapo.backend import TapoBackend, device_error
from rosaos_tapo.plugin import real_backend
from rosaos_tapo.server import build_server
from rosaos_tapo.settings import TapoSettings
from rosaos_tapo.simulator import SimState, SimulatedL530, SimulatedL530Transport, simulated_config

OWNER = ("owner@example.com", "right password")


def free_port() -> int:
    """A loopback port that nothing listens on (bound, then released)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def real_bulb_at(
    port: int, *, username: str = OWNER[0], password: str = OWNER[1], timeout: float = 5
) -> TapoBackend:
    return TapoBackend.real("kitchen_light", "127.0.0.1", username, password, timeout=timeout, port=port)


@contextlib.asynccontextmanager
async def silent_bulb() -> AsyncIterator[int]:
    """A TCP server that accepts connections and never answers: a hung or overloaded bulb."""
    held: list[asyncio.StreamWriter] = []

    async def accept(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        held.append(writer)

    server = await asyncio.start_server(accept, "127.0.0.1", 0)
    try:
        yield int(server.sockets[0].getsockname()[1])
    finally:
        for writer in held:
            writer.close()
        server.close()
        await server.wait_closed()


def _sha256(data: bytes) -> bytes:
    return hashlib.sha256(data).digest()


@contextlib.asynccontextmanager
async def klap_bulb_owned_by(username: str, password: str) -> AsyncIterator[int]:
    """An HTTP server that answers the KLAP v2 handshake as a bulb set up with this account.

    handshake1 proves the bulb knows the owner's hash; kasa refuses to go on when that proof
    does not match the credentials it was given. Requests after the handshake are not served.
    """
    owner_hash = _sha256(hashlib.sha1(username.encode()).digest() + hashlib.sha1(password.encode()).digest())

    async def handshake1(request: web.Request) -> web.Response:
        local_seed, remote_seed = await request.read(), os.urandom(16)
        return web.Response(body=remote_seed + _sha256(local_seed + remote_seed + owner_hash))

    async def handshake2(request: web.Request) -> web.Response:
        return web.Response()

    app = web.Application()
    app.router.add_post("/app/handshake1", handshake1)
    app.router.add_post("/app/handshake2", handshake2)
    runner = web.AppRunner(app)
    await runner.setup()
    site = web.TCPSite(runner, "127.0.0.1", 0)
    await site.start()
    try:
        yield int(runner.addresses[0][1])
    finally:
        await runner.cleanup()


# Unreachable and silent bulbs


async def test_nothing_listening_is_cannot_reach_and_fails_fast() -> None:
    backend = real_bulb_at(free_port(), timeout=5)
    started = time.monotonic()
    with pytest.raises(DeviceError, match=r"^cannot reach Tapo bulb at 127\.0\.0\.1: check it is powered"):
        await backend.start()
    assert time.monotonic() - started < 5


async def test_a_bulb_that_never_answers_is_cannot_reach_within_the_timeout() -> None:
    async with silent_bulb() as port:
        backend = real_bulb_at(port, timeout=0.5)
        started = time.monotonic()
        with pytest.raises(DeviceError, match=r"cannot reach Tapo bulb.*no answer within 0\.5 s"):
            await backend.start()
    assert time.monotonic() - started < 2


async def test_discovery_with_no_answer_is_cannot_reach() -> None:
    backend = TapoBackend.real("kitchen_light", "127.0.0.1", *OWNER, timeout=0.5, connection="discover")
    with pytest.raises(DeviceError, match=r"cannot reach Tapo bulb at 127\.0\.0\.1"):
        await backend.start()


# Credentials


async def test_wrong_credentials_name_the_tp_link_account_settings() -> None:
    async with klap_bulb_owned_by(*OWNER) as port:
        backend = real_bulb_at(port, password="wrong password")
        with pytest.raises(DeviceError) as raised:
            await backend.start()
    assert str(raised.value).startswith(
        "Tapo refused the username/password for 127.0.0.1: use your TP-Link cloud account email "
        "and password in [devices.kitchen_light] username/password"
    )


async def test_right_credentials_get_past_the_handshake() -> None:
    # The control for the test above: the fake bulb does accept its owner, so the refusal
    # there comes from the credentials and not from a broken fake.
    async with klap_bulb_owned_by(*OWNER) as port:
        backend = real_bulb_at(port)
        with pytest.raises(DeviceError) as raised:
            await backend.start()
    assert "refused the username/password" not in str(raised.value)


# Translation of kasa's exceptions


def test_authentication_error_translates_to_the_credentials_message() -> None:
    error = device_error(AuthenticationError("bad hash"), "192.168.1.50", "lamp", 10)
    assert "Tapo refused the username/password for 192.168.1.50" in str(error)
    assert "[devices.lamp] username/password" in str(error)


def test_a_device_side_error_says_the_bulb_rejected_the_request() -> None:
    error = device_error(KasaDeviceError("PARAMS_ERROR"), "192.168.1.50", "lamp", 10)
    assert str(error).startswith("the Tapo bulb at 192.168.1.50 rejected the request")


def test_an_unexpected_answer_suggests_checking_host_and_discovery() -> None:
    error = device_error(KasaException("responded with 404 to handshake1"), "192.168.1.50", "lamp", 10)
    assert "check [devices.lamp] host" in str(error)
    assert 'connection = "discover"' in str(error)


# Devices that are not (fully) lights


class SimulatedP110(SimulatedL530):
    """A Tapo smart plug: same protocol, no light."""

    def _component_nego(self, params: dict[str, Any]) -> tuple[int, Any]:
        return 0, {"component_list": [{"id": "device", "ver_code": 2}, {"id": "time", "ver_code": 1}]}

    def _get_device_info(self, params: dict[str, Any]) -> tuple[int, Any]:
        _, info = super()._get_device_info(params)
        light_keys = {"brightness", "hue", "saturation", "color_temp", "color_temp_range"}
        plug = {key: value for key, value in info.items() if key not in light_keys}
        return 0, {**plug, "type": "SMART.TAPOPLUG", "model": "P110"}


class SimulatedL510(SimulatedL530):
    """A dimmable white-only Tapo bulb: brightness, no colour, no colour temperature."""

    def _component_nego(self, params: dict[str, Any]) -> tuple[int, Any]:
        ids = {"device": 2, "time": 1, "brightness": 1}
        return 0, {"component_list": [{"id": name, "ver_code": ver} for name, ver in ids.items()]}

    def _get_device_info(self, params: dict[str, Any]) -> tuple[int, Any]:
        _, info = super()._get_device_info(params)
        colour_keys = {"hue", "saturation", "color_temp", "color_temp_range"}
        return 0, {**{k: v for k, v in info.items() if k not in colour_keys}, "model": "L510"}


def backend_on(bulb: SimulatedL530) -> TapoBackend:
    config = simulated_config(bulb.instance)
    transport = SimulatedL530Transport(config=config, bulb=bulb)

    async def connect() -> Device:
        device = SmartDevice(config.host, config=config, protocol=SmartProtocol(transport=transport))
        await device.update()
        return device

    return TapoBackend(bulb.instance, config.host, connect, timeout=5)


async def test_a_device_without_a_light_is_refused_naming_its_model() -> None:
    backend = backend_on(SimulatedP110("desk_plug", SimState()))
    with pytest.raises(DeviceError, match=r"is a Tapo P110, which has no light"):
        await backend.start()


async def test_colour_on_a_white_only_bulb_says_what_it_can_do() -> None:
    backend = backend_on(SimulatedL510("hall_light", SimState(on=True)))
    await backend.start()
    with pytest.raises(DeviceError, match=r"hall_light \(L510\) has no colour LEDs"):
        await backend.set_color(120, 100)
    await backend.close()


async def test_colour_temperature_on_a_dimmable_only_bulb_says_what_it_can_do() -> None:
    backend = backend_on(SimulatedL510("hall_light", SimState(on=True)))
    await backend.start()
    with pytest.raises(DeviceError, match=r"cannot change its colour temperature; use set_brightness"):
        await backend.set_color_temp(2700)
    await backend.close()


async def test_a_device_error_reaches_the_model_as_the_tool_error_text() -> None:
    backend = backend_on(SimulatedL510("hall_light", SimState(on=True)))
    await backend.start()
    ctx = DeviceContext(
        instance="hall_light", description="Hall light", settings=TapoSettings(), backend="sim"
    )
    async with Client(build_server(ctx, backend)) as client:
        result = await client.call_tool("set_color_name", {"name": "red"}, raise_on_error=False)
    await backend.close()
    assert result.is_error
    assert "hall_light (L510) has no colour LEDs" in str(result.content[0])


async def test_a_white_only_bulb_reports_zero_hue_and_colour_temperature() -> None:
    backend = backend_on(SimulatedL510("hall_light", SimState(on=True, brightness=30)))
    await backend.start()
    state = await backend.state()
    await backend.close()
    assert state.model_dump() == {"on": True, "brightness": 30, "hue": 0, "saturation": 0, "color_temp": 0}


# Settings the real backend needs


def real_context(**settings: Any) -> DeviceContext:
    return DeviceContext(
        instance="kitchen_light", description="", settings=TapoSettings(**settings), backend="real"
    )


def test_real_backend_without_host_says_to_set_it() -> None:
    with pytest.raises(DeviceError, match=r"\[devices\.kitchen_light\] needs host"):
        real_backend(real_context(username="a@b.c", password="pw"))


def test_real_backend_without_credentials_says_which_account() -> None:
    with pytest.raises(DeviceError, match=r"needs username and password .* TP-Link cloud"):
        real_backend(real_context(host="192.168.1.50"))


def test_real_backend_with_full_settings_is_not_simulated() -> None:
    backend = real_backend(real_context(host="192.168.1.50", username="a@b.c", password="pw"))
    assert (backend.host, backend.simulated) == ("192.168.1.50", False)
