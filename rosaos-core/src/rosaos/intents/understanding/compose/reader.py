"""Compositional reading: a sentence → clauses → (action, devices, quantities) → tool calls.

This is the engine's general reader, used when a sentence is not an exact template match
(:func:`rosaos.intents.understanding.generalize.understand`). It knows no sentence: it peels off
discourse (:mod:`.speech`), cuts clauses, reads each clause's action from a lexicon
(:mod:`.actions`) and its devices from their names, kinds, places and descriptions
(:mod:`.references`), and turns the action into a call of the capability the device's driver
declares (:mod:`rosaos.intents.grammar.capabilities`), filling each argument by its meaning.

A clause that names no device means the device of the clause before ("undock the turtlebot then
roll it forward"), else the one device that can do it ("louder" with one speaker). A clause that
is only a device repeats the action before ("turn off the kitchen light and the desk lamp"), or
addresses the next ("robot, return to base"). A clause that is neither a command nor a device
("ugh, it's so bright, …") is commentary and dropped when another clause is a command. A need
("I need some light to sew at the table", "it's too dark in the kitchen") is the action that
meets it, on the one device that fits the place it names.

Never guessed: negations, questions, "stop" (another part of the engine answers those), a
device the world does not have. Several devices where one was meant get "which one?".
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from rosaos.intents.grammar.capabilities import Capabilities
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.compose.actions import Said, read_action, restate
from rosaos.intents.understanding.compose.complaints import complaint, vague_level
from rosaos.intents.understanding.compose.device_calls import DeviceCalls
from rosaos.intents.understanding.compose.references import Reference, References
from rosaos.intents.understanding.compose.scenes import read_scene
from rosaos.intents.understanding.compose.speech import (
    asks,
    clauses,
    negated_command,
    normalise,
    remark,
    says_stop,
)
from rosaos.intents.understanding.match_result import MatchResult, build_result
from rosaos.intents.understanding.readings import RANK_DRIVER, Focus, Reading, ReadingContext

LiteralReading = Callable[[str, Focus], Reading | None]
_OCCASION = re.compile(
    r"^(?:it's\s+|its\s+|it\s+is\s+)?(?:(?:about\s+)?time\s+(?:to|for)\b|bedtime\b|good\s+(?:morning|night|evening)\b)"
)
"""A clause that says what time it is for ("time to work", "good night"), once no action is read in it."""


_SWAP = re.compile(
    r"\b(?:swap|switch|flip|trade|exchange|reverse)\b(?P<what>.*?)\b(?:around|round|over)$"
    r"|\b(?:swap|exchange|trade)\b(?P<rest>.*)$"
    r"|\bthe (?:on|lit) (?:one|1) off\b.*\bthe (?:off|unlit|dark) (?:one|1) on\b"
    r"|\bthe (?:off|unlit|dark) (?:one|1) on\b.*\bthe (?:on|lit) (?:one|1) off\b"
)
"""Two devices trading states: "swap the lights", "switch them around", "turn the on one off and
the off one on". Each of two on/off devices is toggled, which trades their states."""
_DETERMINERS = frozenset({"the", "my", "our", "your", "this", "that", "these", "those", "a", "an"})
_ONE = re.compile(r"\b(?:the|that|this)\s+(?:other\s+)?(?:one|1)\b")
_LOUDNESS = re.compile(r"\b(?:loud|noisy|quiet|blaring|deafening|can'?t hear)\b")
_LIGHTNESS = re.compile(r"\b(?:bright|dark|dim|gloomy|harsh|glaring|blinding|too light)\b")
_COMMENT = re.compile(r"^(?:it'?s|it is|that'?s|that is|this is|i'?m|i am|we'?re|so|wow|man|god|gosh)\b")


@dataclass(frozen=True)
class _Clause:
    text: str
    said: Said | None
    reference: Reference
    about: tuple[str, ...] = ()
    """For a remark, the devices it is about: "it" in the next clause means them ("the kitchen
    light is too bright, dim it")."""


class Composer(DeviceCalls):
    """Reads sentences compositionally against one world's devices and their capabilities."""

    def __init__(self, context: ReadingContext, devices: Sequence[DeviceVocabulary], language: str) -> None:
        self.context = context
        self.language = language
        self.capabilities: dict[str, Capabilities] = {}
        self.descriptions = {device.name: device.description for device in devices}
        values: dict[str, set[str]] = {"colour": set(), "play": set()}
        for device in devices:
            file = device.mapping_file()
            if file is None or file.capabilities is None:
                continue
            self.capabilities[device.name] = file.capabilities
            for capability in file.capabilities.can:
                if capability.values:
                    values.setdefault(capability.does, set()).update(file.list_values(capability.values))
        self.colours = frozenset(values["colour"])
        self.genres = frozenset(values["play"])
        self.references = References(devices, self.capabilities, language)

    def read(
        self, text: str, focus: Focus, literal: LiteralReading, complete: bool = False
    ) -> MatchResult | None:
        """What ``text`` asks for, or None when this reader cannot say (left to the engine).

        ``complete``: None when a clause that is not plainly a remark ("it's so bright") would be
        dropped as commentary. The engine asks this of the reader before its template paths,
        which may read such a clause ("… and some jazz") where this reader cannot.
        """
        if not self.capabilities or not self.language.startswith("en"):
            return None
        plain = normalise(text)
        if negated_command(plain) or asks(plain) or says_stop(plain):
            return None
        swapped = _SWAP.search(" ".join(clauses(plain)))
        if swapped is not None:
            return self._swap(text, swapped.group("what") or swapped.group("rest") or "", focus)
        pieces = [piece for piece in clauses(plain) if piece]
        if not pieces:
            return None
        parsed = [self._clause(piece) for piece in pieces]
        parsed = self._addressed(parsed)
        parsed = [_as_said(clause, text) for clause in parsed]
        commands = [clause for clause in parsed if clause.said is not None]
        if not commands or all(
            clause.said and clause.said.action == "colour_temperature" for clause in commands
        ):
            scene = read_scene(plain)
            set_scene = self._scene(scene, plain, focus) if scene is not None else None
            if set_scene is not None:
                return build_result(self.context, text, [set_scene], focus is not None)
        if not commands:
            need = self._need(plain, focus)
            return build_result(self.context, text, [need], focus is not None) if need else None
        readings: list[Reading] = []
        before: tuple[str, ...] = ()
        last: _Clause | None = None
        for index, clause in enumerate(parsed):
            reading: Reading | None
            if index == 0 and self._exclaimed(clause) and len(commands) > 0:
                continue  # "Movie night! Dim the lamp …": an exclamation before the commands
            if clause.said is None and clause.reference.named and last is not None and last.said:
                again = _again(last, clause.text)
                reading = self._reading(again, last.said, clause.reference, before, focus)
            elif clause.said is None:
                reading = literal(clause.text, focus) if clause.reference.named else None
                if reading is None and (not clause.reference.named or _commentary(clause.text)):
                    if complete and not _commentary(clause.text):
                        return None  # "… and some jazz": maybe a command the templates read
                    before = clause.about or before
                    continue  # commentary around a command: "ugh, it's so bright, ..."
            else:
                reading = self._reading(clause.text, clause.said, clause.reference, before, focus)
                if reading is None or not (reading.actionable or reading.issue):
                    reading = literal(clause.text, focus) or reading
                elif _vague(clause.said):
                    reading = _driver_amount(reading, literal(clause.text, focus))
                last = clause
            if reading is None or not (reading.actionable or reading.issue):
                return None
            readings.append(reading)
            before = tuple(reading.calls) or before
        return build_result(self.context, text, readings, focus is not None)

    def _clause(self, text: str) -> _Clause:
        said = None if remark(text) else read_action(text, self.colours, self.genres)
        if said is None or (said.action == "level" and "change" in said.values):
            said = vague_level(text) or said  # "really low", "nice and dim": a level, not a step
        if remark(text) or (_settable(said) and complaint(text) is not None and vague_level(text) is None):
            # "the baby is napping", "I'm heading out": why, not what. Its words are neither an
            # action ("out") nor a device this world lacks ("baby"). "This light is too cold" is
            # a complaint (a step the other way, :meth:`_need`), not a white to set.
            about = self.references.resolve(text)
            devices = () if about.unknown else about.devices
            return _Clause(text, None, Reference(), devices or self._felt(text))
        if _OCCASION.match(text) and (
            said is None or not any(self._capability(d, said) for d in self.capabilities)
        ):
            return _Clause(text, None, Reference())  # "…, time to work/sleep": when, not what
        reference = self.references.resolve(said.rest if said else text)
        return _Clause(text, said, reference)

    def _exclaimed(self, clause: _Clause) -> bool:
        """A short opening that names nothing here and asks nothing ("movie night", "party
        time", "finally"): not a device this world lacks ("the tv, turn it on" names one)."""
        words = clause.text.split()
        return (
            clause.said is None
            and clause.reference.unknown
            and len(words) <= 3
            and words[0] not in _DETERMINERS
            and not self.references.names_a_kind(clause.text)
        )

    def _felt(self, remark: str) -> tuple[str, ...]:
        """The one device a remark about a level is about: "it's a bit loud" is the one player."""
        family = "volume" if _LOUDNESS.search(remark) else "brightness" if _LIGHTNESS.search(remark) else None
        if family is None:
            return ()
        said = Said("level", {"change": 10}, family=family)
        able = tuple(device for device in self.capabilities if self._capability(device, said))
        return able if len(able) == 1 else ()

    @staticmethod
    def _addressed(parsed: list[_Clause]) -> list[_Clause]:
        """A clause that is only a device, before a command that names none, addresses it; so
        does one said last, after such a command ("turn your head to the right, Reachy")."""
        merged: list[_Clause] = []
        index = 0
        while index < len(parsed):
            clause = parsed[index]
            after = index + 1
            while (
                clause.said is None
                and clause.reference.named
                and not clause.reference.unknown
                and after + 1 < len(parsed)
                and parsed[after].said is None
                and not parsed[after].reference.named
                and _commentary(parsed[after].text)
            ):
                after += 1  # "Reachy, we're done for today, go to sleep": a remark between
            following = parsed[after] if after < len(parsed) else None
            if (
                clause.said is None
                and clause.reference.named
                and following is not None
                and following.said is not None
                and not following.reference.named
            ):
                merged.append(_Clause(f"{clause.text}, {following.text}", following.said, clause.reference))
                index = after + 1
                continue
            following = parsed[index + 1] if index + 1 < len(parsed) else None
            if (
                clause.said is not None
                and not clause.reference.named
                and not clause.reference.pronoun
                and following is not None
                # said last, or before only remarks ("wake up, Reachy, time to work")
                and all(rest.said is None and not rest.reference.named for rest in parsed[index + 2 :])
                and following.said is None
                and following.reference.named
                and not following.reference.unknown
            ):
                merged.append(_Clause(f"{clause.text}, {following.text}", clause.said, following.reference))
                index += 2
                continue
            merged.append(clause)
            index += 1
        return merged

    def _reading(
        self, text: str, said: Said, reference: Reference, before: tuple[str, ...], focus: Focus
    ) -> Reading | None:
        if reference.unknown:
            return None
        if reference.named:
            named = list(reference.devices)
            if before and _ONE.search(text):
                # "turn on the kitchen light and switch off the one in the living room": "one" is
                # a device of the kind just named.
                kinds = {kind for device in before for kind in self.references.kinds(device)}
                named = [device for device in named if self.references.kinds(device) & kinds]
                reference = replace(reference, plural=False)
        elif before:
            named = list(before)
        else:
            named = list(self.capabilities)
        if focus is not None:
            named = [device for device in named if device in focus]
        able = {device: capability for device in named if (capability := self._capability(device, said))}
        if not able and not reference.named and before:
            # "kitchen light on, music louder": the device before cannot, so any that can.
            return self._reading(text, said, reference, (), focus)
        if not able:
            return None
        plural = reference.plural or (not reference.named and bool(before) and len(before) > 1)
        if (
            len(able) > 1
            and not plural
            and len(meant := [device for device in able if device in before]) == 1
        ):
            # "the kitchen feels cold, make that light warmer": of the lights, the one just named.
            able = {device: able[device] for device in meant}
        if len(able) > 1 and not plural:
            return self.context.clarify(text, 0, RANK_DRIVER, list(able))
        if reference.both and len(able) != 2:
            return self.context.clarify(text, 0, RANK_DRIVER, list(able))
        steps = {device: self._step(device, capability, said) for device, capability in able.items()}
        calls = {
            device: [step, *self._also(device, able[device], said)] for device, step in steps.items() if step
        }
        if len(calls) != len(steps):
            return None
        return Reading(restate(text, said), RANK_DRIVER, len(text), calls=calls)


def _settable(said: Said | None) -> bool:
    """Whether ``said`` is at most a setting a complaint's words could be misread as ("too
    cold" as a cold white): a play or a motion in the same clause is what is asked."""
    return said is None or said.action in ("level", "colour", "colour_temperature")


def _commentary(clause: str) -> bool:
    """A clause that comments rather than commands: dropped beside a command."""
    return _COMMENT.match(clause) is not None or remark(clause)


def _again(command: _Clause, devices: str) -> str:
    """``command`` said again of other ``devices``, for the reply: "turn off the kitchen light"
    and "the desk lamp" → "turn off the desk lamp" (``devices`` alone when the command's own
    device words are not one stretch of it)."""
    said = command.said.rest if command.said is not None else ""
    if said and said in command.text:
        return command.text.replace(said, devices, 1)
    return devices


_VAGUE = ("change", "kelvin_change", "distance", "angle")


def _vague(said: Said) -> bool:
    """An amount the words do not say ("dim", "a bit closer"): the reader's default size."""
    return said.quantity is None and any(meaning in said.values for meaning in _VAGUE)


def _driver_amount(reading: Reading, template: Reading | None) -> Reading:
    """``reading``, or the driver's own template for the same clause when it makes the same calls
    but says how much a vague word is ("dim" is 25 % for the Tapo driver): as when the
    sentence is a template, the driver's author decides that, not the reader's default."""
    if template is None or not template.actionable:
        return reading
    same = {device: [step.tool for step in steps] for device, steps in reading.calls.items()}
    if same != {device: [step.tool for step in steps] for device, steps in template.calls.items()}:
        return reading
    return template


def _as_said(clause: _Clause, text: str) -> _Clause:
    """``clause`` with a free-text query or text to say in the user's own words ("Take Five",
    "Here Comes the Sun"): the reader works on lowercase and digits, a search or a voice on
    what was said."""
    said = clause.said
    meaning = "query" if "query" in (said.values if said else {}) else "text"
    if said is None or not isinstance(query := said.values.get(meaning), str):
        return clause
    words, size = text.split(), len(query.split())
    for start in range(len(words)):
        for end in range(start + max(1, size - 3), min(len(words), start + size + 3) + 1):
            window = " ".join(words[start:end]).strip(" ,.!?;:\"'")
            if normalise(window) == query:
                values = {**said.values, meaning: window}
                return replace(
                    clause, text=clause.text.replace(query, window), said=replace(said, values=values)
                )
    return clause
