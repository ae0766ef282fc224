"""Receipts: redaction, result bounds, and how safety decisions are read from tool outcomes."""

from __future__ import annotations

from rosaos.receipts import (
    REDACTED,
    RESULT_LIMIT,
    Receipt,
    SafetyDecision,
    receipts_text,
    redact,
    result_text,
    safety_of,
    safety_report,
    secret_args_meta,
    secret_args_of,
)


def test_marked_and_secret_looking_arguments_are_redacted_at_any_depth() -> None:
    arguments = {"pin": "1234", "host": "bulb", "auth": {"password": "x", "user": "ana"}, "api_key": "k"}
    assert redact(arguments, secret_args_of(secret_args_meta("pin"))) == {
        "pin": REDACTED,
        "host": "bulb",
        "auth": REDACTED,
        "api_key": REDACTED,
    }
    assert redact({"login": {"password": "x", "user": "ana"}}) == {
        "login": {"password": REDACTED, "user": "ana"}
    }


def test_long_results_are_cut_and_say_so() -> None:
    text = result_text({"data": "x" * 5000})
    assert len(text) < RESULT_LIMIT + 60 and text.endswith("characters in all)")


def test_a_refused_error_is_a_refusal_and_a_safety_key_is_read() -> None:
    refused = safety_of(
        None, "Error calling tool 'drive': refused: publishing to topic /x is not in the allow-list"
    )
    assert refused is not None and (refused.decision, refused.rule) == ("refused", "allow-list")
    assert safety_of(None, "the bulb is offline") is None
    clamped = safety_of({"ok": True, **safety_report("clamped", "max speed", "0.5 -> 0.3")}, None)
    assert clamped == SafetyDecision(decision="clamped", rule="max speed", detail="0.5 -> 0.3")
    assert safety_of({"ok": True}, None) is None


def test_many_receipts_show_the_first_and_last_ones() -> None:
    receipts = [Receipt(device="d", tool=f"t{i}", ok=True, started=i, duration=0) for i in range(30)]
    lines = receipts_text(receipts).splitlines()
    assert lines[0] == "tool calls:" and lines[1].startswith("- d.t0()") and lines[-1].startswith("- d.t29()")
    assert "- ... (10 more calls)" in lines and len(lines) == 22
