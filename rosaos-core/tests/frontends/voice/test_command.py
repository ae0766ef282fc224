"""``rosaos voice``: its options, its ``[voice]`` config, and clear exits when something is missing."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from rosaos.cli import app
from rosaos.config import load_config
from rosaos.devices.serve import bind_socket
from rosaos.frontends.voice.command import _line
from rosaos.frontends.voice.pipeline import Heard
from rosaos.frontends.voice.stt import wav_bytes

from .voice_support import tone


@pytest.fixture(autouse=True)
def isolated(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A data dir and working dir of the test's own; no user config."""
    monkeypatch.setenv("ROSAOS_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.delenv("ROSAOS_CONFIG", raising=False)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture
def wav(tmp_path: Path) -> Path:
    path = tmp_path / "tone.wav"
    path.write_bytes(wav_bytes(tone(0.5)))
    return path


def voice(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["voice", *args])
    return result.exit_code, result.output


def test_the_voice_table_configures_the_front_end(tmp_path: Path) -> None:
    (tmp_path / "rosaos.toml").write_text(
        '[voice]\nwake_phrase = "hey robot"\nfollow_up_seconds = 5\nstt = "groq"\nsilence_seconds = 0.8\n'
    )
    voice_config = load_config().voice
    assert (voice_config.wake_phrase, voice_config.follow_up_seconds) == ("hey robot", 5)
    assert (voice_config.stt, voice_config.silence_seconds) == ("groq", 0.8)


def test_the_defaults_are_offline_and_near_the_issue_s_timings() -> None:
    voice_config = load_config().voice
    assert (voice_config.stt, voice_config.vad, voice_config.wake_phrase) == ("local", "silero", "hello")
    assert (voice_config.silence_seconds, voice_config.min_speech_seconds, voice_config.chunk_seconds) == (
        0.55,
        0.35,
        0.032,
    )
    # A whole command ends after a pause people leave between turns (~200 ms); issue 25.
    assert voice_config.complete_silence_seconds == 0.18 and voice_config.vocabulary_bias


def test_a_bad_voice_setting_names_the_key(tmp_path: Path, wav: Path) -> None:
    (tmp_path / "rosaos.toml").write_text('[voice]\nstt = "whisper-on-mars"\n')
    code, output = voice("--wav", str(wav))
    assert code == 2
    assert "voice.stt" in output


def test_wav_and_source_together_are_refused(wav: Path) -> None:
    code, output = voice("--wav", str(wav), "--source", "mic")
    assert code == 2 and "not both" in output


def test_an_unknown_source_is_refused() -> None:
    code, output = voice("--source", "telepathy")
    assert code == 2 and "mic or reachy" in output


def test_a_missing_wav_file_is_reported_first() -> None:
    code, output = voice("--wav", "missing.wav")
    assert code == 1 and "no such WAV file" in output


def test_without_a_kernel_token_it_says_to_start_the_kernel(wav: Path) -> None:
    code, output = voice("--wav", str(wav))
    assert code == 2 and "rosaos up" in output


def test_a_kernel_that_is_not_running_is_a_clear_exit_2(tmp_path: Path, wav: Path) -> None:
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "token").write_text("secret")
    sock = bind_socket("127.0.0.1", 0)  # bound, not listening: connection refused
    try:
        code, output = voice("--wav", str(wav), "--url", f"http://127.0.0.1:{sock.getsockname()[1]}")
    finally:
        sock.close()
    assert code == 2
    assert "cannot reach the rosaOS kernel" in output and "rosaos up" in output


def test_the_printed_lines_say_what_was_heard_and_sent() -> None:
    times = {"start": 0.06, "end": 1.57, "stt_seconds": 0.8, "vad_delay": 0.6}
    assert _line(Heard("transcript", "Hello. Turn on the light.", times)) == (
        "heard 'Hello. Turn on the light.' (0.06-1.57 s, stt 0.80 s)"
    )
    sent = _line(Heard("sent", "Turn on the light.", {**times, "event_id": 4}))
    assert sent == "  → sent 'Turn on the light.' to the kernel as event 4"
    assert _line(Heard("speech", "", times)) is None
