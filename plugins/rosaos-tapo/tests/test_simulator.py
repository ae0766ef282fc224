"""The simulated L530E: kasa's own SmartDevice and Light module run on it, unmodified."""

from __future__ import annotations

from typing import Any

import pytest
from kasa import DeviceError as KasaDeviceError
from kasa import DeviceType, LightState, Module
from kasa.exceptions import SmartErrorCode
from kasa.protocols import SmartProtocol
from kasa.smart import SmartDevice

from rosaos.drivers import DeviceContext, DeviceError
from rosaos_tapo.plugin import sim_backend
from rosaos_tapo.settings import TapoSettings
from rosaos_tapo.simulator import (
    SimState,
    SimulatedL530,
    SimulatedL530Transport,
    simulated_config,
)


async def kasa_device_on(bulb: SimulatedL530) -> SmartDevice:
    """A kasa SmartDevice talking to ``bulb`` through kasa's SmartProtocol, updated once."""
    config = simulated_config(bulb.instance)
    transport = SimulatedL530Transport(config=config, bulb=bulb)
    device = SmartDevice(config.host, config=config, protocol=SmartProtocol(transport=transport))
    await device.update()
    return device


# kasa sees an L530E


async def test_kasa_recognises_the_sim_as_a_tapo_l530_bulb() -> None:
    device = await kasa_device_on(SimulatedL530("kitchen_light", SimState()))
    assert (device.model, device.device_type, device.alias) == ("L530", DeviceType.Bulb, "kitchen_light")


async def test_kasa_loads_its_light_modules_for_the_sim() -> None:
    device = await kasa_device_on(SimulatedL530("kitchen_light", SimState()))
    for module in (Module.Light, Module.Brightness, Module.Color, Module.ColorTemperature):
        assert module in device.modules


async def test_kasa_reads_the_sim_state_through_its_light_module() -> None:
    state = SimState(on=True, brightness=42, hue=300, saturation=90, color_temp=0)
    device = await kasa_device_on(SimulatedL530("lamp", state))
    light = device.modules[Module.Light]
    assert device.is_on
    assert (light.brightness, light.hsv.hue, light.hsv.saturation, light.color_temp) == (42, 300, 90, 0)


# kasa's own setters change the simulated bulb


async def test_kasa_set_brightness_reaches_the_sim() -> None:
    bulb = SimulatedL530("lamp", SimState(on=True))
    device = await kasa_device_on(bulb)
    await device.modules[Module.Light].set_brightness(25)
    assert bulb.state.brightness == 25


async def test_kasa_set_hsv_reaches_the_sim_and_leaves_white_mode() -> None:
    bulb = SimulatedL530("lamp", SimState(on=True, color_temp=4000))
    device = await kasa_device_on(bulb)
    await device.modules[Module.Light].set_hsv(120, 100)
    assert (bulb.state.hue, bulb.state.saturation, bulb.state.color_temp) == (120, 100, 0)


async def test_kasa_set_color_temp_reaches_the_sim_and_keeps_hue() -> None:
    bulb = SimulatedL530("lamp", SimState(on=True, hue=120, saturation=100, color_temp=0))
    device = await kasa_device_on(bulb)
    await device.modules[Module.Light].set_color_temp(3000)
    assert (bulb.state.color_temp, bulb.state.hue) == (3000, 120)


async def test_kasa_turn_off_reaches_the_sim() -> None:
    bulb = SimulatedL530("lamp", SimState(on=True))
    device = await kasa_device_on(bulb)
    await device.turn_off()
    assert bulb.state.on is False


async def test_the_sim_rejects_what_the_bulb_rejects_with_a_kasa_error() -> None:
    bulb = SimulatedL530("lamp", SimState(on=True, brightness=50))
    device = await kasa_device_on(bulb)
    with pytest.raises(KasaDeviceError) as raised:
        await device.modules[Module.Light].set_state(LightState(brightness=150))
    assert raised.value.error_code is SmartErrorCode.PARAMS_ERROR
    assert bulb.state.brightness == 50


def test_the_sim_answers_an_unknown_method_like_the_bulb() -> None:
    bulb = SimulatedL530("lamp", SimState())
    assert bulb.call("get_latest_fw", None) == (SmartErrorCode.UNKNOWN_METHOD_ERROR.value, None)


# The backend's device is that kasa device


async def test_sim_backend_device_is_a_kasa_smart_device(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        assert isinstance(bulb.backend.device, SmartDevice)
        assert bulb.backend.simulated is True


async def test_tool_calls_show_in_kasas_light_module(open_bulb: Any) -> None:
    async with open_bulb(on=False) as bulb:
        await bulb.call("set_color", hue=240, saturation=100, brightness=40)
        light = bulb.backend.device.modules[Module.Light]
        assert bulb.backend.device.is_on
        assert (light.hsv.hue, light.hsv.saturation, light.brightness, light.color_temp) == (240, 100, 40, 0)


# The sim table


def test_sim_table_defaults_to_an_off_warm_white_bulb() -> None:
    assert SimState.from_sim("lamp", {}) == SimState(
        on=False, brightness=100, hue=0, saturation=0, color_temp=2700
    )


def test_sim_table_unknown_key_is_an_error_naming_the_allowed_keys() -> None:
    with pytest.raises(DeviceError) as raised:
        SimState.from_sim("kitchen_light", {"on": True, "colour": "red"})
    message = str(raised.value)
    assert "devices.kitchen_light.sim" in message
    assert "'colour'" in message
    assert "on, brightness, hue, saturation, color_temp" in message


@pytest.mark.parametrize(
    ("key", "value"), [("brightness", 0), ("brightness", 101), ("hue", 361), ("color_temp", 2000)]
)
def test_sim_table_out_of_range_value_is_an_error_naming_the_key(key: str, value: int) -> None:
    with pytest.raises(DeviceError, match=rf"devices\.lamp\.sim: {key}: "):
        SimState.from_sim("lamp", {key: value})


def test_sim_backend_rejects_an_unknown_sim_key_when_built() -> None:
    ctx = DeviceContext(
        instance="lamp", description="A lamp", settings=TapoSettings(), backend="sim", sim={"dimmed": True}
    )
    with pytest.raises(DeviceError, match="unknown key"):
        sim_backend(ctx)
