"""What `rosaos chat` prints: device and model text never reaches the terminal as escape sequences."""

from __future__ import annotations

import pytest

from rosaos.frontends.chat import format_update, printable


@pytest.mark.parametrize(
    ("raw", "shown"),
    [
        ("\x1b[2J\x1b[Hcleared", "cleared"),  # clear screen, cursor home
        ("\x1b]0;pwned\x07title", "title"),  # set the window title (OSC ... BEL)
        ("\x1b]8;;http://evil.example\x1b\\link\x1b]8;;\x1b\\", "link"),  # OSC 8 hyperlink
        ("red \x1b[31malert\x1b[0m", "red alert"),
        ("bell\x07 and \x9bcsi", "bell and csi"),
        ("two\nlines\tand a tab", "two\nlines\tand a tab"),
        ("Lumière 30 %", "Lumière 30 %"),
    ],
)
def test_printable_drops_escapes_and_controls_but_keeps_text(raw: str, shown: str) -> None:
    assert printable(raw) == shown


def test_a_device_notice_is_a_line_and_other_events_are_not() -> None:
    notice = {"kind": "device_notice", "source": "device", "payload": {}}
    text = "[Device notice] speaker: playback ended after Clair de Lune by Claude Debussy"
    assert format_update({"kind": "event", "text": text, "data": notice}) == f"  · {text}"
    typed = {"kind": "event", "text": "[User typed] hi", "data": {"kind": "user_typed"}}
    assert format_update(typed) is None  # the user's own line is already on the screen


def test_a_reply_with_escapes_is_shown_without_them() -> None:
    line = format_update({"kind": "kernel_reply", "text": "Done\x1b[2J: light on"})
    assert line == "rosaos: Done: light on"


def test_a_process_report_reads_as_words_not_as_the_models_header() -> None:
    ok = {
        "kind": "worker_callback",
        "payload": {"process_id": 3, "status": "ok", "output": "Done: light on."},
    }
    text = "[Process callback] process=3 status=ok output=Done: light on."
    assert (
        format_update({"kind": "event", "text": text, "data": ok})
        == "  · process 3 reported: Done: light on."
    )
    failed = {
        "kind": "worker_callback",
        "payload": {"process_id": 4, "status": "failed", "output": None, "error": "lamp\x1b[2J unreachable"},
    }
    line = format_update({"kind": "event", "text": "[Process callback] ...", "data": failed})
    assert line == "  · process 4 ended failed: lamp unreachable"
