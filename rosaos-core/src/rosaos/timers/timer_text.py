"""Timer times for people and models: "23:00" → the next 23:00, "in 10 minutes", "late by 2 h".

Clock times are the kernel machine's local time: "stop the music at 11 pm" means 11 pm where
the robot is. Stored times are UTC (:mod:`rosaos.timers.timer_book`).
"""

from __future__ import annotations

import re
from datetime import datetime, timedelta

from rosaos.events.types import TimerFired
from rosaos.timers.timer_phrases import duration_text

_CLOCK = re.compile(r"^\s*(?P<hour>\d{1,2})(?::(?P<minute>\d{2}))?(?::(?P<second>\d{2}))?\s*$")


class DueTimeError(ValueError):
    """A time that cannot be a timer's: the message says the accepted forms."""


def resolve_due(in_seconds: float | None, at: str | None, now: datetime) -> datetime:
    """When a timer set at ``now`` (aware) falls due: after ``in_seconds``, or at clock time ``at``.

    ``at`` is ``HH:MM`` (24-hour, local; the next such moment, today or tomorrow) or an ISO 8601
    date and time (local when it has no offset). Exactly one of the two must be given.
    """
    if (in_seconds is None) == (at is None):
        raise DueTimeError("give exactly one of in_seconds (a delay) or at (a clock time such as 23:00)")
    if in_seconds is not None:
        if in_seconds <= 0:
            raise DueTimeError(f"in_seconds must be positive, not {in_seconds}")
        return now + timedelta(seconds=in_seconds)
    assert at is not None
    local_now = now.astimezone()
    clock = _CLOCK.match(at)
    if clock is not None:
        hour, minute = int(clock["hour"]), int(clock["minute"] or 0)
        second = int(clock["second"] or 0)
        if hour > 23 or minute > 59 or second > 59:
            raise DueTimeError(f"{at!r} is not a time of day; use HH:MM from 00:00 to 23:59")
        due = local_now.replace(hour=hour, minute=minute, second=second, microsecond=0)
        return due if due > local_now else due + timedelta(days=1)
    try:
        when = datetime.fromisoformat(at.strip())
    except ValueError:
        raise DueTimeError(
            f"{at!r} is not a time; use HH:MM (24-hour, local) or an ISO 8601 date and time"
        ) from None
    when = when if when.tzinfo is not None else when.astimezone()  # naive = local
    if when <= now:
        raise DueTimeError(f"{at} has already passed; give a time in the future")
    return when


def clock_text(when: datetime, now: datetime) -> str:
    """``22:10``, or ``Tue 07:00`` when it is not today (local time)."""
    local, local_now = when.astimezone(), now.astimezone()
    text = local.strftime("%H:%M")
    if local.date() != local_now.date():
        text = local.strftime("%a ") + text
    return text


def due_text(when: datetime, now: datetime) -> str:
    """``at 22:10 (in 10 minutes)``."""
    return f"at {clock_text(when, now)} (in {duration_text((when - now).total_seconds())})"


def render_timer_fired(payload: TimerFired) -> str:
    """What the kernel model reads: ``[Timer fired] timer=3 due=22:10:00`` then the action.

    A late firing adds ``(late by 2 h 5 min: …)`` to the first line, so the model can say so."""
    head = f"[Timer fired] timer={payload.timer_id} due={payload.due.astimezone().strftime('%H:%M:%S')}"
    if payload.late:
        head += f" (late by {duration_text(payload.late_seconds)}: the kernel was not running then)"
    action = " ".join(payload.action.splitlines())  # one line: it cannot start an event of its own
    return f"{head}\naction: {action}"
