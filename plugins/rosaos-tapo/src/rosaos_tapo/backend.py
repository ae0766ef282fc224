"""The Tapo backend: one python-kasa ``Device`` with a ``Light`` module, real or simulated.

Both backends are the same class over the same kasa code; they differ only in how the device
is reached:

- ``real``: ``Device.connect`` to the bulb's IP over the SMART protocol with KLAP encryption,
  authenticated with the owner's TP-Link cloud account; or, for firmware that predates KLAP,
  UDP discovery first (``Discover.discover_single``), which asks the bulb how it talks.
- ``sim``: a kasa ``SmartDevice`` whose transport is an in-process simulated L530E
  (:mod:`rosaos_tapo.simulator`).

Every operation takes a lock (kasa's device object is not meant for interleaved commands),
runs under the instance's timeout, re-reads the bulb, and returns the new :class:`BulbState`.
kasa failures become :class:`rosaos.drivers.DeviceError` with a fix-it message.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Awaitable, Callable
from typing import Annotated

from kasa import (
    AuthenticationError,
    Credentials,
    Device,
    DeviceConfig,
    DeviceConnectionParameters,
    Discover,
    KasaException,
    Light,
    LightState,
    Module,
)
from kasa import DeviceError as KasaDeviceError
from kasa.deviceconfig import DeviceEncryptionType, DeviceFamily
from kasa.exceptions import _ConnectionError  # kasa's only name for "TCP connect failed"
from kasa.protocols import SmartProtocol
from kasa.smart import SmartDevice
from pydantic import BaseModel, Field

from rosaos.drivers import DeviceBackend, DeviceError
from rosaos_tapo.settings import Connection
from rosaos_tapo.simulator import SimState, SimulatedL530, SimulatedL530Transport, simulated_config

NEUTRAL_KELVIN = 4000
"""Where "warmer"/"cooler" start from when the bulb shows a colour (no white temperature)."""


class BulbState(BaseModel):
    """What ``get_state`` returns, and every other tool after acting: the bulb as it is now."""

    on: bool = Field(description="Whether the light is on.")
    brightness: Annotated[int, Field(ge=0, le=100, description="Brightness in percent.")]
    hue: Annotated[int, Field(ge=0, le=360, description="Hue in degrees (colour mode).")]
    saturation: Annotated[int, Field(ge=0, le=100, description="Saturation in percent (colour mode).")]
    color_temp: Annotated[
        int, Field(ge=0, description="White colour temperature in kelvin; 0 while in colour mode.")
    ]


class TapoBackend(DeviceBackend):
    """A Tapo bulb behind python-kasa. Build it with :meth:`real` or :meth:`simulated_bulb`."""

    def __init__(
        self,
        instance: str,
        host: str,
        connect: Callable[[], Awaitable[Device]],
        *,
        timeout: float,
        simulated: bool = False,
    ) -> None:
        self.instance = instance
        self.host = host
        self.timeout = timeout
        self.simulated = simulated
        self._connect = connect
        self._device: Device | None = None
        self._lock = asyncio.Lock()
        self.notify: Callable[..., object] | None = None
        """``DeviceContext.notify``: set by the plugin, so losing the bulb and finding it again are notices."""
        self._unreachable = False

    @classmethod
    def real(
        cls,
        instance: str,
        host: str,
        username: str,
        password: str,
        *,
        timeout: float,
        port: int | None = None,
        connection: Connection = "klap",
    ) -> TapoBackend:
        """A backend for the bulb at ``host``, logging in with the TP-Link account of its owner."""
        credentials = Credentials(username, password)
        request_timeout = math.ceil(timeout)  # kasa counts whole seconds
        config = DeviceConfig(
            host=host,
            timeout=request_timeout,
            port_override=port,
            credentials=credentials,
            connection_type=DeviceConnectionParameters(
                DeviceFamily.SmartTapoBulb, DeviceEncryptionType.Klap, login_version=2
            ),
        )

        async def connect() -> Device:
            if connection == "klap":
                return await Device.connect(config=config)
            device = await Discover.discover_single(
                host, discovery_timeout=request_timeout, timeout=request_timeout, credentials=credentials
            )
            if device is None:
                raise TimeoutError()  # no discovery answer: reported as "cannot reach"
            try:
                await device.update()  # Device.connect updates; discovery does not
            except BaseException:
                await device.disconnect()
                raise
            return device

        return cls(instance, host, connect, timeout=timeout)

    @classmethod
    def simulated_bulb(cls, instance: str, state: SimState) -> TapoBackend:
        """A backend for an in-process simulated L530E starting in ``state``."""
        config = simulated_config(instance)
        transport = SimulatedL530Transport(config=config, bulb=SimulatedL530(instance, state))

        async def connect() -> Device:
            device = SmartDevice(config.host, config=config, protocol=SmartProtocol(transport=transport))
            await device.update()  # what Device.connect does for a real bulb
            return device

        return cls(instance, config.host, connect, timeout=5.0, simulated=True)

    # Lifecycle

    async def start(self) -> None:
        """Connect (log in, negotiate components, read state); check the device is a light."""
        try:
            async with asyncio.timeout(self.timeout):
                device = await self._connect()
        except (KasaException, TimeoutError) as error:
            raise device_error(error, self.host, self.instance, self.timeout) from None
        if Module.Light not in device.modules:
            await device.disconnect()
            raise DeviceError(
                f"{self.host} is a Tapo {device.model}, which has no light; "
                f"the tapo driver drives Tapo bulbs and light strips: check [devices.{self.instance}] host"
            )
        self._device = device

    async def close(self) -> None:
        """Close the HTTP session to the bulb (nothing to do for the simulator)."""
        if self._device is not None:
            await self._device.disconnect()
            self._device = None

    @property
    def device(self) -> Device:
        """The connected kasa device. Raises :class:`DeviceError` before :meth:`start`."""
        if self._device is None:
            raise DeviceError(f"{self.instance}: the Tapo backend is not started")
        return self._device

    @property
    def light(self) -> Light:
        """The device's kasa ``Light`` module: brightness, HSV and colour temperature."""
        return self.device.modules[Module.Light]

    @property
    def has_color(self) -> bool:
        """True for colour bulbs (L530, L535, L630, light strips)."""
        return Module.Color in self.device.modules

    @property
    def has_color_temp(self) -> bool:
        """True for bulbs with tunable white LEDs."""
        return Module.ColorTemperature in self.device.modules

    # Operations. Each returns the state read back from the bulb after acting.

    async def state(self) -> BulbState:
        """Read the bulb's current state (it may have been changed by a switch or the app)."""
        return await self._run(None)

    async def turn_on(self) -> BulbState:
        """Turn the light on at its last brightness and colour."""
        return await self._run(lambda: self.device.turn_on())

    async def turn_off(self) -> BulbState:
        """Turn the light off."""
        return await self._run(lambda: self.device.turn_off())

    async def toggle(self) -> BulbState:
        """Turn the light off if it is on, on if it is off."""

        async def command() -> None:
            await self.device.update()  # toggle what the bulb is now, not what we last saw
            await self.device.set_state(not self.device.is_on)

        return await self._run(command)

    async def set_brightness(self, brightness: int) -> BulbState:
        """Set brightness in percent and turn the light on; 0 turns it off instead."""
        if brightness == 0:
            return await self.turn_off()
        return await self._run(lambda: self.light.set_state(LightState(light_on=True, brightness=brightness)))

    async def adjust_brightness(self, change: int) -> BulbState:
        """Change brightness by ``change`` percentage points (1-100 after clamping) and turn on."""

        async def command() -> None:
            await self.device.update()
            brightness = min(100, max(1, self.light.brightness + change))
            await self.light.set_state(LightState(light_on=True, brightness=brightness))

        return await self._run(command)

    async def set_color_temp(self, kelvin: int) -> BulbState:
        """Switch to white light at ``kelvin`` and turn the light on."""
        if not self.has_color_temp:
            instead = "use set_color or set_brightness" if self.has_color else "use set_brightness"
            raise DeviceError(
                f"{self.instance} ({self.device.model}) cannot change its colour temperature; {instead}"
            )
        low, high = self.device.modules[Module.ColorTemperature].valid_temperature_range
        if not low <= kelvin <= high:
            raise DeviceError(
                f"{kelvin} K is outside what {self.instance} can do: use {low}-{high} K "
                "(lower is warmer, higher is cooler)"
            )
        return await self._run(lambda: self.light.set_state(LightState(light_on=True, color_temp=kelvin)))

    async def adjust_color_temp(self, change: int) -> BulbState:
        """Make white light warmer (negative ``change``) or cooler by ``change`` kelvin, and turn on.

        Starts from the current colour temperature, or from neutral white (4000 K) when the bulb
        shows a colour; the result is kept within what the bulb can do.
        """
        if not self.has_color_temp:
            raise DeviceError(
                f"{self.instance} ({self.device.model}) cannot change its colour temperature; "
                "use set_brightness"
            )

        async def command() -> None:
            await self.device.update()
            low, high = self.device.modules[Module.ColorTemperature].valid_temperature_range
            current = self.light.color_temp or NEUTRAL_KELVIN
            kelvin = min(high, max(low, current + change))
            await self.light.set_state(LightState(light_on=True, color_temp=kelvin))

        return await self._run(command)

    async def set_color(self, hue: int, saturation: int, brightness: int | None = None) -> BulbState:
        """Switch to colour mode at ``hue``/``saturation`` (and ``brightness``) and turn on."""
        if not self.has_color:
            raise DeviceError(
                f"{self.instance} ({self.device.model}) has no colour LEDs; "
                "use set_color_temp for warm/cool white or set_brightness"
            )
        # color_temp=0 is how the SMART protocol leaves white mode (kasa's set_hsv sends it too).
        state = LightState(light_on=True, hue=hue, saturation=saturation, color_temp=0, brightness=brightness)
        return await self._run(lambda: self.light.set_state(state))

    async def _run(self, command: Callable[[], Awaitable[object]] | None) -> BulbState:
        async with self._lock:
            try:
                async with asyncio.timeout(self.timeout):
                    if command is not None:
                        await command()
                    await self.device.update()
            except (KasaException, TimeoutError) as error:
                failure = device_error(error, self.host, self.instance, self.timeout)
                if isinstance(error, TimeoutError | _ConnectionError):
                    self._reachability(False, str(failure))
                raise failure from None
            self._reachability(True, "")
            return self._snapshot()

    def _reachability(self, reachable: bool, reason: str) -> None:
        """Post ``unreachable`` when the bulb stops answering, ``reachable`` when it answers again."""
        if reachable == (not self._unreachable):
            return
        self._unreachable = not reachable
        if self.notify is not None:
            if reachable:
                self.notify("reachable", None, message=f"{self.instance} answers again")
            else:
                self.notify(
                    "unreachable", {"error": reason[:300]}, message=f"{self.instance} is not answering"
                )

    def _snapshot(self) -> BulbState:
        device, light = self.device, self.light
        hue, saturation = (light.hsv.hue, light.hsv.saturation) if self.has_color else (0, 0)
        return BulbState(
            on=device.is_on,
            brightness=light.brightness if Module.Brightness in device.modules else 100,
            hue=hue,
            saturation=saturation,
            color_temp=light.color_temp if self.has_color_temp else 0,
        )


def device_error(error: BaseException, host: str, instance: str, timeout: float) -> DeviceError:
    """Translate a python-kasa (or timeout) failure into a :class:`DeviceError` saying what to do."""
    where = f"[devices.{instance}]"
    if isinstance(error, AuthenticationError):
        return DeviceError(
            f"Tapo refused the username/password for {host}: use your TP-Link cloud account email "
            f"and password in {where} username/password (the ones of the Tapo app that set up the bulb)"
        )
    # kasa's TimeoutError and asyncio's both subclass the builtin TimeoutError.
    if isinstance(error, TimeoutError | _ConnectionError):
        reason = f"no answer within {timeout:g} s" if _is_bare_timeout(error) else str(error)
        return DeviceError(
            f"cannot reach Tapo bulb at {host}: check it is powered and on this network; "
            f"fix the address in {where} host if it changed (give the bulb a fixed IP in your router) "
            f"[{reason}]"
        )
    if isinstance(error, KasaDeviceError):
        return DeviceError(f"the Tapo bulb at {host} rejected the request: {error}")
    return DeviceError(
        f"the device at {host} did not talk like a Tapo bulb: {error}; check {where} host, and if "
        'the bulb has old firmware (before KLAP), set connection = "discover" there'
    )


def _is_bare_timeout(error: BaseException) -> bool:
    return isinstance(error, TimeoutError) and not str(error)
