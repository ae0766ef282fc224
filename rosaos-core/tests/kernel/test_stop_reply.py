"""The stop's reply names each device as a person would: "the kitchen light", but "Spotify"."""

from __future__ import annotations

from typing import Any, cast

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.kernel.stopping import StoppedDevice, StoppedProcess, Stopper


def endpoint(name: str, driver: str) -> DeviceEndpoint:
    return DeviceEndpoint(name, driver, "exclusive", False, "", "", None, "", "ready")


def stopper() -> Stopper:
    endpoints = {"spotify": endpoint("spotify", "spotify"), "dog": endpoint("dog", "ros2")}
    return Stopper(cast(Any, None), lambda: endpoints, lambda name: ())


def test_a_device_named_after_its_product_is_called_by_that_name_and_another_by_its_kind() -> None:
    reply = stopper().summary(
        [
            StoppedDevice(
                device="dog", processes=[StoppedProcess(id=3, task="walk forward")], safe_stop=True
            ),
            StoppedDevice(device="spotify", was="playing", safe_stop=True),
        ],
        [],
        explicit=False,
        names=[],
    )
    assert reply == (
        "Stopped the dog: it was doing 'walk forward' (process 3), now terminated. "
        "Stopped Spotify: it was playing."
    )


def test_nothing_to_stop_names_the_devices_asked_for_the_same_way() -> None:
    reply = stopper().summary([], [], explicit=True, names=["spotify", "dog"])
    assert reply == "Nothing to stop on Spotify, the dog."
