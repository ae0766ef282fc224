"""Test a driver's ``intents.yaml`` the way the offline engine reads it: a sentence in, a tool call out.

::

    from rosaos.testing import IntentProbe

    probe = IntentProbe(SPEC, devices={"kitchen light": "kitchen_light", "bedside": "bedroom_light"})
    assert probe.match("dim the kitchen light") == ("kitchen_light", "adjust_brightness", {"change": -25})
    assert probe.match("turn on the garage light") is None

:meth:`IntentProbe.understand` runs the whole engine instead (templates, then the compositional
reader over the file's ``capabilities:``), for everyday sentences no template lists::

    assert probe.understand("oh, could you put the kitchen light at half?") == (
        "kitchen_light", "set_brightness", {"brightness": 50})

The probe's ``match`` runs the engine's own code for a driver's templates (:mod:`rosaos.intents.understanding.readings`):
the same recognition, the same ``{device}`` names, the same choice among several parses, the same
slot filling (``"{slot}"`` arguments; whole numbers as ``int``). It reads the file alone, one
sentence as one command: Home Assistant's templates and skip words (which the engine adds when the
file maps HA intents), and what :class:`~rosaos.intents.understanding.matching.IntentMatcher` does around the
templates (several commands in one sentence, for one), are not part of the probe.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from pathlib import Path
from typing import Any, NamedTuple

from hassil import recognize_all
from hassil.intents import TextSlotList

from rosaos.drivers import DriverSpec
from rosaos.intents.grammar.intents_file import IntentsFile
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.matching import MAX_RESULTS_PER_SOURCE, IntentMatcher
from rosaos.intents.understanding.readings import Reading, ReadingContext, driver_reading

PROBE_DRIVER = "probe"
"""Driver name the probe's devices get when it reads a bare file (a :class:`DriverSpec` has its own)."""


class IntentMatch(NamedTuple):
    """The one tool call a sentence stands for; compares equal to ``(device, tool, args)``."""

    device: str
    """The instance the sentence names (or the only one, for a template without ``{device}``)."""
    tool: str
    args: dict[str, Any]


class IntentProbe:
    """A driver's intents, matched against a few named devices as the offline engine matches them.

    ``intents`` is a :class:`~rosaos.drivers.DriverSpec` (its ``intents`` file is used) or the
    path of an ``intents.yaml``. ``devices`` fills ``{device}``: spoken name → instance name, e.g.
    ``{"robot dog": "dog"}``. As in the engine, every instance also answers to its own name with
    spaces for underscores (``kitchen_light`` → "kitchen light"). ``language`` picks the file as
    the engine does: ``intents.<language>.yaml`` next to ``intents.yaml``, or ``intents.yaml``
    itself when it is in that language.

    Raises ``ValueError`` when there is no intents file in that language or ``devices`` is empty,
    and :class:`~rosaos.intents.grammar.intents_file.IntentsFileError` when the file does not load.
    """

    def __init__(
        self, intents: DriverSpec | Path, *, devices: Mapping[str, str], language: str = "en"
    ) -> None:
        if isinstance(intents, DriverSpec):
            path, driver = intents.intents, intents.name
        else:
            path, driver = intents, PROBE_DRIVER
        if path is None:
            raise ValueError(f"driver {driver!r} ships no intents file (DriverSpec.intents is None)")
        if not devices:
            raise ValueError("devices is empty: name at least one instance, e.g. {'lamp': 'lamp'}")
        aliases: dict[str, list[str]] = {}
        for spoken, instance in devices.items():
            aliases.setdefault(instance, []).append(spoken)
        sources = {
            name: DeviceVocabulary(name=name, driver=driver, aliases=tuple(spoken), intents=path)
            for name, spoken in aliases.items()
        }
        file = next(iter(sources.values())).intents_file(language)
        if file is None:
            raise ValueError(
                f"{path}: not in {language!r}, and there is no {path.stem}.{language}{path.suffix}"
            )
        self.intents_file: IntentsFile = file
        """The loaded file, for tests of its lists and ``homeassistant:`` table."""
        self.language = language
        self._sources = list(sources.values())
        self._matcher: IntentMatcher | None = None
        self._context = ReadingContext(sources, language)
        self._intents = file.intents()
        self._devices = list(sources)
        spoken_names = sorted({name for source in sources.values() for name in source.spoken_names(language)})
        self._device_list = TextSlotList.from_tuples(
            [(name, name) for name in spoken_names], allow_template=False
        )

    def match(self, sentence: str) -> IntentMatch | None:
        """The tool call the engine makes for ``sentence``, or None when the engine would not act.

        None when no template matches, a ``"{slot}"`` argument has no value, or the match does not
        settle on one device (the engine would then ask "which one?").
        """
        best = self._best(" ".join(sentence.split()))
        if best is None or not best.actionable:
            return None
        [step] = [step for steps in best.calls.values() for step in steps]  # a template calls one tool
        return IntentMatch(step.device, step.tool, step.args)

    def understand(self, sentence: str) -> IntentMatch | None:
        """The one tool call the whole offline engine makes for ``sentence``, or None when it would
        not make exactly one (it asks, refuses, or does not understand)."""
        if self._matcher is None:
            self._matcher = IntentMatcher(self._sources, self.language)
        result = self._matcher.match(sentence)
        steps = [step for process in result.processes for step in process.plan.steps]
        if not result.is_exact or len(steps) != 1:
            return None
        return IntentMatch(steps[0].device, steps[0].tool, steps[0].args)

    def _best(self, clause: str) -> Reading | None:
        """The engine's pick among the parses of ``clause`` (``IntentMatcher`` does the same per driver)."""
        results = recognize_all(
            clause, self._intents, slot_lists={"device": self._device_list}, language=self.language
        )
        readings = []
        for result in itertools.islice(results, MAX_RESULTS_PER_SOURCE):
            action = self.intents_file.actions[result.intent.name]
            reading = driver_reading(self._context, clause, result, self._devices, action)
            if reading is not None:
                readings.append(reading)
        return max(readings, key=Reading.sort_key) if readings else None
