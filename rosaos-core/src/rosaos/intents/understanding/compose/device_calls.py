"""From an action read in a clause to a device's tool call, and the readings built from those alone.

A part of :class:`~rosaos.intents.understanding.compose.reader.Composer` (moved out of
``reader.py``): which capability a device's driver declares for an action (:meth:`_capability`),
the step that calls it with each argument filled by its meaning (:meth:`_step`), and the readings
that need no clause of their own: two devices swapping on and off, a scene, a need or complaint.
"""

from __future__ import annotations

import re

from rosaos.events.plan import PlanStep
from rosaos.intents.grammar.capabilities import Capabilities, Capability
from rosaos.intents.understanding.compose.complaints import complaint
from rosaos.intents.understanding.compose.references import References
from rosaos.intents.understanding.compose.said import Said
from rosaos.intents.understanding.compose.scenes import Scene
from rosaos.intents.understanding.match_result import MatchResult, build_result
from rosaos.intents.understanding.readings import RANK_DRIVER, Focus, Reading, ReadingContext

_NEED_LIGHT = re.compile(
    r"\b(?:need|want|could use|would like|give me|get me|some)\b.*\b(?:light|lighting)\b"
    r"|\bcan'?t see\b|\b(?:too|so|very|pretty|quite|really) dark\b|\bpitch black\b|\bdark in here\b"
)
_TOO_BRIGHT = re.compile(r"\b(?:too|so|very|way too|really) bright\b|\bhurts my eyes\b")
_TOO_LOUD = re.compile(r"\b(?:too|so|very|way too|really) loud\b|\bcan'?t hear myself\b")
_TOO_QUIET = re.compile(r"\b(?:too|so|very|really) quiet\b|\bcan'?t hear (?:it|the music|anything)\b")


class DeviceCalls:
    """The device-call half of :class:`~rosaos.intents.understanding.compose.reader.Composer`."""

    context: ReadingContext
    capabilities: dict[str, Capabilities]
    descriptions: dict[str, str]
    references: References

    def _also(self, device: str, first: Capability, said: Said) -> list[PlanStep]:
        """The other steps of an action a driver declares more than once with nothing to fill:
        "face forward" turns the Reachy's body to the front, then its head."""
        if first.args or said.values or said.family:
            return []
        declared = self.capabilities[device].doing(said.action, self.descriptions.get(device, ""))
        return [
            PlanStep(device=device, tool=other.tool, args=dict(other.fixed))
            for other in declared[1:]
            if not other.args
        ]

    def _capability(self, device: str, said: Said) -> Capability | None:
        declared = self.capabilities.get(device)
        if declared is None:
            return None
        description = self.descriptions.get(device, "")
        wanted = set(said.values)
        if said.action == "level":
            families = [said.family] if said.family else ["brightness", "volume", "level"]
            options = [
                capability for family in families for capability in declared.doing(family, description)
            ]
        else:
            options = declared.doing(said.action, description)
        for capability in options:
            meanings = set(capability.args.values())
            if wanted <= meanings or (not wanted and not meanings):
                return capability
        return None

    @staticmethod
    def _step(device: str, capability: Capability, said: Said) -> PlanStep | None:
        args = dict(capability.fixed)
        for meaning, value in said.values.items():
            name = capability.argument(meaning)
            if name is not None:
                args[name] = int(value) if isinstance(value, float) and value.is_integer() else value
                if not capability.allows(name, value):
                    return None  # out of the device's range: the engine refuses, never clips
        return PlanStep(device=device, tool=capability.tool, args=args)

    def _swap(self, text: str, phrase: str, focus: Focus) -> MatchResult | None:
        """Two devices trade on and off: each is toggled. Which two: those ``phrase`` names, else
        the only two that switch; more than two ask which."""
        said = Said("toggle")
        reference = self.references.resolve(phrase)
        if reference.unknown:
            return None
        named = list(reference.devices) if reference.named else list(self.capabilities)
        able = [
            device
            for device in named
            if self._capability(device, said) and (focus is None or device in focus)
        ]
        if len(able) > 2:
            return build_result(self.context, text, [self.context.clarify(text, 0, RANK_DRIVER, able)], False)
        if len(able) != 2:
            return None
        calls = {
            device: [step]
            for device in able
            if (capability := self._capability(device, said)) is not None
            and (step := self._step(device, capability, said)) is not None
        }
        reading = Reading(text, RANK_DRIVER, len(text), calls=calls)
        return build_result(self.context, text, [reading], focus is not None)

    def _scene(self, scene: Scene, text: str, focus: Focus) -> Reading | None:
        """Every device that can take part in ``scene``, in the place ``text`` names if any."""
        place = self.references.resolve(text)
        calls: dict[str, list[PlanStep]] = {}
        for said in scene.actions:
            for device in self.capabilities:
                capability = self._capability(device, said)
                if capability is None or (focus is not None and device not in focus):
                    continue
                if place.named and not place.unknown and device not in place.devices:
                    continue
                step = self._step(device, capability, said)
                if step is not None:
                    calls.setdefault(device, []).append(step)
        if len(calls) > 1 and not (place.named and not place.unknown):
            # "movie night" with lights in three rooms: which room is a real question.
            return self.context.clarify(text, 0, RANK_DRIVER, list(calls))
        return Reading(text, RANK_DRIVER, len(text), calls=calls) if calls else None

    def _need(self, text: str, focus: Focus) -> Reading | None:
        """A need or a complaint → the action that meets it, on the one device that fits."""
        if _NEED_LIGHT.search(text):
            said = Said("level", {"level": 100}, family="brightness")
        elif (complained := complaint(text)) is not None:
            said = complained  # "way too loud", "a bit dark", "too blue": a step the other way
        elif _TOO_BRIGHT.search(text):
            said = Said("level", {"change": -20}, family="brightness")
        elif _TOO_LOUD.search(text):
            said = Said("level", {"change": -20}, family="volume")
        elif _TOO_QUIET.search(text):
            said = Said("level", {"change": 20}, family="volume")
        else:
            return None
        reference = self.references.resolve(text)
        able = [device for device in self.capabilities if self._capability(device, said)]
        if focus is not None:
            able = [device for device in able if device in focus]
        fitting = [device for device in able if device in reference.devices] if reference.named else []
        if reference.named and not reference.unknown and not fitting:
            return None  # "the dog is too loud", "too bright in the kitchen" (only a speaker there)
        if len(fitting) == 1 or (not fitting and len(able) == 1):
            [device] = fitting or able
            capability = self._capability(device, said)
            step = self._step(device, capability, said) if capability is not None else None
            return Reading(text, RANK_DRIVER, len(text), calls={device: [step]}) if step else None
        if len(able) > 1:
            return self.context.clarify(text, 0, RANK_DRIVER, fitting or able)
        return None
