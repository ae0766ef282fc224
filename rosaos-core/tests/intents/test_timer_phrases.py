"""Reading timer requests: delays and clock times in digits or words, listing, cancelling."""

from __future__ import annotations

from datetime import datetime

import pytest

from rosaos.timers.timer_phrases import (
    CancelTimer,
    ListTimers,
    SetTimer,
    parse_clock,
    parse_duration,
    read_timer_request,
)

EVENING = datetime(2026, 11, 25, 20, 0).astimezone()


@pytest.mark.parametrize(
    ("text", "seconds"),
    [
        ("ten minutes", 600),
        ("10 min", 600),
        ("twenty-five minutes", 1500),
        ("1.5 hours", 5400),
        ("an hour and a half", 5400),
        ("two and a half hours", 9000),
        ("half an hour", 1800),
        ("a quarter of an hour", 900),
        ("2 h 30 min", 9000),
        ("1 hour and 5 minutes", 3900),
        ("90s", 90),
        ("a couple of minutes", 120),
        ("three days", 259200),
    ],
)
def test_durations(text: str, seconds: float) -> None:
    assert parse_duration(text) == seconds


@pytest.mark.parametrize("text", ["the kitchen", "a while", "minutes", "ten", "0 minutes", ""])
def test_what_is_not_a_duration(text: str) -> None:
    assert parse_duration(text) is None


@pytest.mark.parametrize(
    ("text", "clock"),
    [
        ("11 pm", "23:00"),
        ("11:30 pm", "23:30"),
        ("eleven thirty pm", "23:30"),
        ("23:15", "23:15"),
        ("7 in the morning", "07:00"),
        ("half past ten", "22:30"),  # 10:30 has passed at 20:00; 22:30 is the sooner
        ("quarter to nine tonight", "20:45"),
        ("ten past six", "06:10"),
        ("noon", "12:00"),
        ("midnight", "00:00"),
        ("12 am", "00:00"),
        ("12 pm", "12:00"),
        ("9 o'clock".replace("o'clock", "oclock"), "21:00"),
    ],
)
def test_clock_times(text: str, clock: str) -> None:
    found = parse_clock(text, EVENING)
    assert found is not None and found[0] == clock


@pytest.mark.parametrize("text", ["25:00", "13 pm", "tea time", "50 percent"])
def test_what_is_not_a_clock_time(text: str) -> None:
    assert parse_clock(text, EVENING) is None


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("Turn off the light in ten minutes.", SetTimer("turn off the light", in_seconds=600)),
        ("in 1.5 hours, stop the music", SetTimer("stop the music", in_seconds=5400)),
        ("In five minutes turn on the lamp", SetTimer("turn on the lamp", in_seconds=300)),
        ("stop the music at 11 p.m.", SetTimer("stop the music", at="23:00")),
        ("at half past seven turn on the lamp", SetTimer("turn on the lamp", at="07:30")),
        ("set a timer for 20 minutes to turn off the fan", SetTimer("turn off the fan", in_seconds=1200)),
        (
            "dim the light to 50 percent after 3 minutes",
            SetTimer("dim the light to 50 percent", in_seconds=180),
        ),
        ("turn on the light tomorrow at 7 am", SetTimer("turn on the light", at="2026-11-26T07:00")),
        ("stop the music at 11", SetTimer("stop the music", at="23:00", weak=True)),
        ("stop the music at 11pm tonight", SetTimer("stop the music", at="23:00")),
        ("turn off the fan in 10 minutes from now", SetTimer("turn off the fan", in_seconds=600)),
        ("at 7.30pm, turn on the porch light", SetTimer("turn on the porch light", at="19:30")),
    ],
)
def test_setting(text: str, expected: SetTimer) -> None:
    assert read_timer_request(text, EVENING) == expected


@pytest.mark.parametrize(
    "text",
    [
        "what timers are set?",
        "list my timers",
        "Any timers?",
        "do I have any timers",
        "which timers are running",
    ],
)
def test_listing(text: str) -> None:
    assert read_timer_request(text, EVENING) == ListTimers()


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("cancel that timer", CancelTimer()),
        ("Cancel the timer, please", CancelTimer()),
        ("cancel timer 3", CancelTimer(timer_id=3)),
        ("delete timer number two", CancelTimer(timer_id=2)),
        ("cancel all timers", CancelTimer(cancel_all=True)),
        ("cancel the light timer", CancelTimer(matching="light")),
        ("remove the timer for the bedroom light", CancelTimer(matching="bedroom light")),
    ],
)
def test_cancelling(text: str, expected: CancelTimer) -> None:
    assert read_timer_request(text, EVENING) == expected


@pytest.mark.parametrize(
    "text",
    [
        "is the alarm on?",
        "cancel the alarm",
        "turn on the light in the kitchen",
        "play music in the living room",
        "turn off the kitchen light",
        "set the brightness to 40",
    ],
)
def test_commands_without_a_time_are_not_timers(text: str) -> None:
    assert read_timer_request(text, EVENING) is None
