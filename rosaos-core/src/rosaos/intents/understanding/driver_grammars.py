"""Each driver's templates in one world, for :class:`~rosaos.intents.understanding.matching.IntentMatcher`.

A driver's ``intents.yaml`` is compiled once per world, with ``{device}`` and ``{area}`` filled
by the names and areas of that driver's devices there (moved out of ``matching.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

from hassil import Intents
from hassil.intents import SlotList, TextSlotList

from rosaos.intents.grammar.intents_file import IntentsFile
from rosaos.intents.grammar.vocabulary import DeviceVocabulary


@dataclass(frozen=True)
class DriverIntents:
    """One driver's templates, compiled, and the slot lists the engine fills for them."""

    driver: str
    file: IntentsFile
    intents: Intents
    devices: list[str]
    device_list: TextSlotList
    area_list: TextSlotList

    @property
    def device_list_names(self) -> list[str]:
        """The spoken names ``{device}`` takes for this driver."""
        return [str(value.value_out) for value in self.device_list.values]

    @property
    def lists(self) -> dict[str, SlotList]:
        """The slot lists the engine fills for this driver's templates."""
        return {"device": self.device_list, "area": self.area_list}


def driver_intents(world: dict[str, DeviceVocabulary], language: str) -> list[DriverIntents]:
    """The templates of each driver that has devices in this world, with their slot lists."""
    by_driver: dict[str, list[DeviceVocabulary]] = {}
    for device in world.values():
        by_driver.setdefault(device.driver, []).append(device)
    drivers = []
    for driver, devices in by_driver.items():
        file = devices[0].intents_file(language)
        if file is None:
            continue
        spoken = {name for device in devices for name in device.spoken_names(language)}
        device_list = TextSlotList.from_tuples(
            [(name, name) for name in sorted(spoken)], allow_template=False
        )
        areas = {area for device in devices for area in device.areas(language)}
        area_list = TextSlotList.from_tuples([(area, area) for area in sorted(areas)], allow_template=False)
        names = [device.name for device in devices]
        drivers.append(DriverIntents(driver, file, file.intents(), names, device_list, area_list))
    return drivers
