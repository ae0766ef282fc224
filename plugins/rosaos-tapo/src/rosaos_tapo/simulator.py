"""A simulated Tapo L530E colour bulb, spoken to through python-kasa's own SMART protocol.

The simulator sits at the lowest layer kasa lets us replace: the *transport*, which on a real
bulb encrypts a JSON request with KLAP and posts it over HTTP. :class:`SimulatedL530Transport`
instead answers the JSON request from an in-memory :class:`SimulatedL530` state. Everything above
it is kasa's real code: ``SmartProtocol`` (request batching, error codes), ``SmartDevice``
(component negotiation, module discovery, updates) and the ``Light``/``Brightness``/``Color``/
``ColorTemperature`` modules. So the ``sim`` backend runs the same code path as a real bulb,
minus the radio.

The message shapes follow what an L530E (hardware 3.0, firmware 1.1.x) answers; only the parts
kasa needs for a light are simulated (no firmware updates, presets, effects or schedules).
"""

from __future__ import annotations

import base64
import hashlib
import json
import time
from typing import Annotated, Any

from kasa import Credentials, DeviceConfig, DeviceConnectionParameters
from kasa.deviceconfig import DeviceEncryptionType, DeviceFamily
from kasa.exceptions import SmartErrorCode
from kasa.transports import BaseTransport
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from rosaos.drivers import DeviceError

COLOR_TEMP_RANGE = (2500, 6500)
"""Kelvin range of the L530E's white LEDs, as the bulb reports it in ``color_temp_range``."""

SIM_CREDENTIALS = Credentials("simulator@rosaos.invalid", "simulator")
"""kasa refuses to talk to a SMART device without credentials; the simulator accepts any."""

# Components an L530E reports in ``component_nego`` that kasa turns into modules we simulate.
# A real bulb lists ~30 more (firmware, schedule, preset, light_effect, ...); leaving them out
# keeps kasa from loading modules whose queries the simulator does not answer.
L530E_COMPONENTS = {
    "device": 2,
    "time": 1,
    "cloud_connect": 1,
    "brightness": 1,
    "color": 1,
    "color_temperature": 1,
}


class SimState(BaseModel):
    """The simulated bulb's light state: the ``sim`` table of a ``tapo`` instance.

    Keys are the ones ``get_state`` returns. ``color_temp`` 0 means colour mode (hue and
    saturation show); otherwise the white LEDs shine at that many kelvin.
    """

    model_config = ConfigDict(extra="forbid")

    on: bool = False
    brightness: Annotated[int, Field(ge=1, le=100)] = 100
    hue: Annotated[int, Field(ge=0, le=360)] = 0
    saturation: Annotated[int, Field(ge=0, le=100)] = 0
    color_temp: int = 2700

    @field_validator("color_temp")
    @classmethod
    def _white_or_colour_mode(cls, value: int) -> int:
        low, high = COLOR_TEMP_RANGE
        if value != 0 and not low <= value <= high:
            raise ValueError(f"must be 0 (colour mode) or {low}-{high} kelvin, got {value}")
        return value

    @classmethod
    def from_sim(cls, instance: str, sim: dict[str, Any]) -> SimState:
        """Validate an instance's ``sim`` table, or raise :class:`DeviceError` saying what is wrong."""
        allowed = ", ".join(cls.model_fields)
        unknown = sorted(set(sim) - set(cls.model_fields))
        if unknown:
            raise DeviceError(
                f"devices.{instance}.sim: unknown key(s) {', '.join(map(repr, unknown))}; "
                f"the Tapo simulator takes: {allowed}"
            )
        try:
            return cls.model_validate(sim)
        except ValidationError as error:
            problems = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in error.errors())
            raise DeviceError(f"devices.{instance}.sim: {problems}") from None


class SimulatedL530:
    """The bulb: its state and its answers to SMART methods, keyed by method name."""

    def __init__(self, instance: str, state: SimState) -> None:
        self.instance = instance
        self.state = state.model_copy()
        digest = hashlib.sha1(instance.encode()).hexdigest().upper()
        self._device_id = "80" + digest[:38]
        # 00-00-5E-00-53-xx is the MAC range RFC 7042 reserves for documentation.
        self._mac = f"00-00-5E-00-53-{digest[:2]}"

    def call(self, method: str, params: dict[str, Any] | None) -> tuple[int, Any]:
        """Answer one SMART method: ``(error_code, result)``, as the bulb would."""
        handler = getattr(self, f"_{method}", None)
        if handler is None:
            return SmartErrorCode.UNKNOWN_METHOD_ERROR.value, None
        return handler(params or {})

    # Method handlers. Names are the SMART method names, prefixed with "_".

    def _component_nego(self, params: dict[str, Any]) -> tuple[int, Any]:
        components = [{"id": name, "ver_code": ver} for name, ver in L530E_COMPONENTS.items()]
        return 0, {"component_list": components}

    def _get_device_info(self, params: dict[str, Any]) -> tuple[int, Any]:
        state = self.state
        return 0, {
            "device_id": self._device_id,
            "fw_ver": "1.1.6 Build 230509 Rel.195312",
            "hw_ver": "3.0",
            "type": "SMART.TAPOBULB",
            "model": "L530",
            "mac": self._mac,
            "hw_id": "0" * 32,
            "fw_id": "0" * 32,
            "oem_id": "0" * 32,
            "ip": "127.0.0.1",
            "specs": "",
            "lang": "en_US",
            "avatar": "bulb",
            "region": "UTC",
            "time_diff": 0,
            "nickname": base64.b64encode(self.instance.encode()).decode(),
            "ssid": base64.b64encode(b"rosaos-sim").decode(),
            "signal_level": 3,
            "rssi": -40,
            "has_set_location_info": False,
            "overheated": False,
            "dynamic_light_effect_enable": False,
            "color_temp_range": list(COLOR_TEMP_RANGE),
            "device_on": state.on,
            "brightness": state.brightness,
            "hue": state.hue,
            "saturation": state.saturation,
            "color_temp": state.color_temp,
        }

    def _get_device_usage(self, params: dict[str, Any]) -> tuple[int, Any]:
        zero = {"today": 0, "past7": 0, "past30": 0}
        return 0, {"time_usage": zero, "power_usage": zero, "saved_power": zero}

    def _get_device_time(self, params: dict[str, Any]) -> tuple[int, Any]:
        return 0, {"timestamp": int(time.time()), "time_diff": 0, "region": "UTC"}

    def _get_connect_cloud_state(self, params: dict[str, Any]) -> tuple[int, Any]:
        return 0, {"status": -1}  # a simulated bulb is never bound to the TP-Link cloud

    def _set_device_info(self, params: dict[str, Any]) -> tuple[int, Any]:
        """Apply a state change the way the L530E firmware does, rejecting what it rejects."""
        low, high = COLOR_TEMP_RANGE
        checks = {
            "device_on": lambda v: isinstance(v, bool),
            "brightness": lambda v: isinstance(v, int) and 1 <= v <= 100,
            "hue": lambda v: isinstance(v, int) and 0 <= v <= 360,
            "saturation": lambda v: isinstance(v, int) and 0 <= v <= 100,
            "color_temp": lambda v: isinstance(v, int) and (v == 0 or low <= v <= high),
        }
        for key, value in params.items():
            if key in checks and not checks[key](value):
                return SmartErrorCode.PARAMS_ERROR.value, None
        update: dict[str, Any] = {}
        if "device_on" in params:
            update["on"] = params["device_on"]
        for key in ("brightness", "hue", "saturation", "color_temp"):
            if key in params:
                update[key] = params[key]
        # A hue or saturation without a colour temperature leaves white mode, as on the bulb.
        if ("hue" in params or "saturation" in params) and "color_temp" not in params:
            update["color_temp"] = 0
        self.state = self.state.model_copy(update=update)
        return 0, None


class SimulatedL530Transport(BaseTransport):
    """A kasa transport that delivers SMART requests to a :class:`SimulatedL530` in-process."""

    DEFAULT_PORT = 80

    def __init__(self, *, config: DeviceConfig, bulb: SimulatedL530) -> None:
        super().__init__(config=config)
        self.bulb = bulb

    @property
    def default_port(self) -> int:
        """The port a real bulb listens on; unused in-process."""
        return self.DEFAULT_PORT

    @property
    def credentials_hash(self) -> str | None:
        """The simulator keeps no credential hash."""
        return None

    async def send(self, request: str) -> dict[str, Any]:
        """Answer a JSON request exactly as the bulb's decrypted response would read."""
        message = json.loads(request)
        method, params = message["method"], message.get("params")
        if method != "multipleRequest":
            error_code, result = self.bulb.call(method, params)
            return _response(error_code, result)
        responses = []
        for sub in params["requests"]:
            error_code, result = self.bulb.call(sub["method"], sub.get("params"))
            responses.append({"method": sub["method"], **_response(error_code, result)})
        return _response(0, {"responses": responses})

    async def close(self) -> None:
        """Nothing to close in-process."""

    async def reset(self) -> None:
        """Nothing to reset: there is no session to renegotiate."""


def _response(error_code: int, result: Any) -> dict[str, Any]:
    # Real bulbs omit "result" for setters that succeed, and for errors.
    return {"error_code": error_code} if result is None else {"error_code": error_code, "result": result}


def simulated_config(instance: str) -> DeviceConfig:
    """The kasa ``DeviceConfig`` a simulated bulb is created with: SMART over KLAP, like an L530E."""
    return DeviceConfig(
        host=f"{instance}.sim",
        credentials=SIM_CREDENTIALS,
        connection_type=DeviceConnectionParameters(
            DeviceFamily.SmartTapoBulb, DeviceEncryptionType.Klap, login_version=2
        ),
    )
