"""A command that leaves its device out, as people do: the matcher's reading of it.

"undock the turtlebot and drive it forward one meter" or "... and drive forward one meter" mean
the turtlebot of the command before; "set it to 30 percent" alone means the only device that fits,
or asks which one. :class:`LeftOutDevices` is a part of
:class:`~rosaos.intents.understanding.matching.IntentMatcher` (moved out of ``matching.py``); it
reads a clause again with a device's name in place of the pronoun, or inserted after its first
words, through the matcher's cached recognition (``_best``).
"""

from __future__ import annotations

import re
from dataclasses import replace

from rosaos.intents.grammar.phrases import pronouns
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.readings import Focus, Reading, ReadingContext

MAX_ELIDED_POSITION = 3
"""A left-out device name is tried after each of a clause's first words, up to this many: the
verb, and a particle ("turn off", "set to"); templates name the device right there."""


class LeftOutDevices:
    """The left-out-device readings of :class:`~rosaos.intents.understanding.matching.IntentMatcher`."""

    devices: dict[str, DeviceVocabulary]
    context: ReadingContext
    language: str
    _filler: set[str]

    def _best(self, clause: str, focus: Focus, device: str | None = None) -> Reading | None:
        """The matcher's best cached reading of ``clause`` (:meth:`IntentMatcher._best`)."""
        raise NotImplementedError

    def _same_command(self, clause: str, device: str, command: str, focus: Focus) -> Reading | None:
        """``clause`` is only another device's name: ``command`` (which acted on ``device``) again,
        for that device. "Turn off the kitchen light and the desk lamp" turns off both."""
        named, leftover = self.context.named_in(clause)
        if len(named) != 1 or any(word not in self._filler for word in leftover):
            return None
        [other] = named
        said = next(
            (
                name
                for name in sorted(self.devices[device].spoken_names(self.language), key=len, reverse=True)
                if re.search(rf"(?<!\w){re.escape(name)}(?!\w)", command, re.IGNORECASE)
            ),
            None,
        )
        if said is None or other == device:
            return None
        spoken = self.devices[other].spoken_names(self.language)[0]
        again = re.sub(rf"(?<!\w){re.escape(said)}(?!\w)", spoken, command, count=1, flags=re.IGNORECASE)
        return self._exactly_for(other, [again], focus)

    def _elided(self, clause: str, device: str, focus: Focus) -> Reading | None:
        """``clause`` read as a command to ``device`` that does not name it, or None.

        "drive it forward" becomes "drive turtlebot forward"; "drive forward" is tried as "drive
        turtlebot forward", "drive forward turtlebot", ... The reading must be exact and about
        ``device`` alone.
        """
        words = clause.split()
        name = self.devices[device].spoken_names(self.language)[0]
        refer = pronouns(self.language)
        if any(word.lower() in refer for word in words):
            candidates = [" ".join(name if word.lower() in refer else word for word in words)]
        else:
            last = min(MAX_ELIDED_POSITION, len(words))
            # Position 0 last: "look around for a person" → "turtlebot, look around for a person".
            positions = [*range(1, last + 1), 0]
            candidates = [" ".join([*words[:at], name, *words[at:]]) for at in positions]
        found = self._exactly_for(device, candidates, focus)
        return replace(found, clause=clause) if found is not None else None

    def _exactly_for(self, device: str, sentences: list[str], focus: Focus) -> Reading | None:
        """The first of ``sentences`` that reads as an exact command to ``device`` alone, or None
        (also when the user's answer to "which one?" ruled ``device`` out)."""
        if focus is not None and device not in focus:
            return None
        for sentence in sentences:
            found = self._best(sentence, frozenset({device}), device)
            if found is not None and found.actionable and set(found.calls) == {device}:
                return found
        return None

    def _elided_anywhere(self, clause: str, focus: Focus) -> Reading | None:
        """``clause`` as a command that leaves out its device, read against every device.

        One device fits: its reading. Several: "which one?". None: None. A pronoun with nothing
        before it to refer to ("turn it off") is read the same way.

        A clause that names a device (by name, kind or place) has not left it out: the literal
        paths before this one read it. Skipping it saves a recognition per candidate position
        and driver (most of the time a sentence no template matches took).
        """
        if self.context.named_in(clause)[0]:
            return None
        fits: list[str] = []
        unfit: set[str] = set()
        for device in self.devices:
            driver = self.devices[device].driver
            if driver in unfit or (focus is not None and device not in focus):
                continue
            if self._elided(clause, device, focus) is not None:
                fits.append(device)
            elif not any(self.devices[other].driver == driver for other in fits):
                # Devices of one driver share its templates (only the name differs), so one
                # that does not fit rules the driver out: a recognition per driver, not per device.
                unfit.add(driver)
        if len(fits) == 1:
            return self._elided(clause, fits[0], focus)
        if fits:
            return self.context.clarify(clause, 0, 0, fits)
        return None
