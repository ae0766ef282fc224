"""The checking rules of the task-success benchmark, exactly as ``../shared/bench/README.md`` states them.

- A plain value must be equal; numbers within 2% or 0.05 absolute, whichever is larger. Booleans
  are not numbers here: ``true`` never equals ``1``.
- Nested dicts compare key by key: the keys ``expect`` names are checked, the rest of the
  nested initial state must keep its value.
- Operators: ``{gt: x}``, ``{lt: x}``, ``{between: [a, b]}`` (strict and inclusive, no tolerance:
  they already state a range), ``{contains: text}`` (case-insensitive) and ``{changed: bool}``
  (compared with the equality rule above, so sensor noise within tolerance is no change).
- Nothing else moves: every key of the initial state (after ``setup``) that ``expect`` does not
  name must keep its value.
- ``reply``: a regex that some reply to the user must match (searched, not anchored).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

from rosaos.bench.tasks import OPERATORS

RELATIVE_TOLERANCE = 0.02
ABSOLUTE_TOLERANCE = 0.05

Rule = Literal["expect", "unchanged"]


@dataclass(frozen=True)
class Difference:
    """One key whose value breaks a rule: what was wanted, and what the device reports."""

    device: str
    key: str
    """Dotted for nested state: ``head.yaw``."""
    expected: Any
    """The ``expect`` value (plain or operator) for rule ``expect``; the initial value for ``unchanged``."""
    actual: Any
    rule: Rule
    present: bool = True
    """False when ``get_state`` did not return the key at all."""

    @property
    def wanted(self) -> str:
        """``expected`` in words: ``> 40``, ``in [100, 140]``, ``unchanged (40)``, ``True``."""
        if self.rule == "unchanged":
            return f"unchanged ({self.expected!r})"
        return describe(self.expected)

    @property
    def got(self) -> str:
        return repr(self.actual) if self.present else "(no such key)"

    def __str__(self) -> str:
        return f"{self.device}.{self.key}: expected {self.wanted}, got {self.got}"


def describe(want: Any) -> str:
    """An ``expect`` value as a reader says it."""
    if is_operator(want):
        operator, operand = next(iter(want.items()))
        match operator:
            case "gt":
                return f"> {operand!r}"
            case "lt":
                return f"< {operand!r}"
            case "between":
                return f"in [{operand[0]!r}, {operand[1]!r}]"
            case "contains":
                return f"contains {operand!r}"
            case "changed":
                return "changed" if operand else "unchanged"
    return repr(want)


def is_operator(want: Any) -> bool:
    """Whether an ``expect`` value is an operator (``{gt: 3}``) rather than a plain value or nested dict."""
    return isinstance(want, dict) and len(want) == 1 and next(iter(want)) in OPERATORS


def world_differences(
    expect: Mapping[str, Mapping[str, Any]],
    before: Mapping[str, Mapping[str, Any]],
    after: Mapping[str, Mapping[str, Any]],
) -> list[Difference]:
    """Every rule broken in the devices of ``after`` (the ones whose state could be read)."""
    differences: list[Difference] = []
    for device in dict.fromkeys([*before, *expect]):
        if device in after:
            differences += device_differences(
                expect.get(device, {}), before.get(device, {}), after[device], device
            )
    return differences


def device_differences(
    expected: Mapping[str, Any],
    before: Mapping[str, Any],
    after: Mapping[str, Any],
    device: str = "",
    prefix: str = "",
) -> list[Difference]:
    """Rules broken by one device's state ``after``, given its initial state ``before``."""
    differences: list[Difference] = []
    for key, want in expected.items():
        path = prefix + str(key)
        present = key in after
        got = after.get(key)
        was = before.get(key)
        if isinstance(want, dict) and not is_operator(want) and isinstance(got, dict):
            differences += device_differences(
                want, was if isinstance(was, dict) else {}, got, device, path + "."
            )
        elif not meets(want, was, got, present):
            differences.append(Difference(device, path, want, got, "expect", present))
    for key, was in before.items():
        if key in expected:
            continue
        path = prefix + str(key)
        got = after.get(key)
        if isinstance(was, dict) and isinstance(got, dict):
            differences += device_differences({}, was, got, device, path + ".")
        elif key not in after or not values_equal(was, got):
            differences.append(Difference(device, path, was, got, "unchanged", key in after))
    return differences


def meets(want: Any, before: Any, got: Any, present: bool = True) -> bool:
    """Whether ``got`` satisfies one ``expect`` value; ``before`` is the key's initial value."""
    if not is_operator(want):
        return present and values_equal(want, got)
    operator, operand = next(iter(want.items()))
    if operator == "changed":
        return (not values_equal(before, got)) == bool(operand)
    if operator == "contains":
        return _contains(got, str(operand))
    if not _is_number(got):
        return False
    if operator == "gt":
        return bool(got > operand)
    if operator == "lt":
        return bool(got < operand)
    low, high = operand
    return bool(low <= got <= high)


def values_equal(want: Any, got: Any) -> bool:
    """The plain-value rule: numbers within tolerance, dicts key by key (``want``'s keys), lists item by item."""
    if isinstance(want, bool) or isinstance(got, bool):
        return isinstance(want, bool) and isinstance(got, bool) and want == got
    if _is_number(want):
        return _is_number(got) and abs(got - want) <= max(RELATIVE_TOLERANCE * abs(want), ABSOLUTE_TOLERANCE)
    if isinstance(want, dict):
        return isinstance(got, dict) and all(k in got and values_equal(v, got[k]) for k, v in want.items())
    if isinstance(want, list | tuple):
        return (
            isinstance(got, list | tuple)
            and len(got) == len(want)
            and all(values_equal(w, g) for w, g in zip(want, got, strict=True))
        )
    return bool(want == got)


def reply_matches(pattern: str, replies: Iterable[str]) -> bool:
    """Whether some reply to the user matches the task's ``reply`` regex (anywhere in it)."""
    compiled = re.compile(pattern)
    return any(compiled.search(reply) for reply in replies)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _contains(got: Any, text: str) -> bool:
    needle = text.casefold()
    if isinstance(got, str):
        return needle in got.casefold()
    if isinstance(got, list):  # e.g. a queue of titles: some item contains it
        return any(isinstance(item, str) and needle in item.casefold() for item in got)
    return False
