"""Speech: the engine order, the offline fallback, and the cloud engines against a loopback fake."""

from __future__ import annotations

import time
import wave
from pathlib import Path

import pytest

from rosaos.drivers import DeviceError
from rosaos_reachy.settings import ReachySettings
from rosaos_reachy.speech import Speaker
from rosaos_reachy.tts import ElevenLabsTts, LocalTts, OpenAISpeechTts, TtsError, build_engines, wav_duration

from .reachy_support import FakeOpenAI


def speaker(tmp_path: Path, **settings: object) -> Speaker:
    config = ReachySettings.model_validate({"audio_output": "file", **settings})
    return Speaker(build_engines(config), tmp_path / "speech", tmp_path, None, config.audio_output)


async def test_espeak_ng_speaks_offline_and_returns_before_the_sentence_ends(tmp_path: Path) -> None:
    started = time.monotonic()
    report = await speaker(tmp_path).say("The kitchen light is on.")
    took = time.monotonic() - started
    assert report.engine == "local" and report.output == "file"
    assert report.seconds > 1.0 and took < report.seconds  # returns as playback starts
    with wave.open(str(tmp_path / report.file)) as wav:
        assert wav.getnframes() > 0
    assert [reason.split(":")[0] for reason in report.skipped] == ["elevenlabs", "groq", "openai"]


async def test_the_configured_order_is_kept_and_local_is_always_last(tmp_path: Path) -> None:
    names = [e.name for e in build_engines(ReachySettings(tts_engines=["local", "openai", "groq"]))]
    assert names == ["openai", "groq", "local"]


async def test_an_openai_compatible_endpoint_speaks_first_when_configured(
    tmp_path: Path, fake_openai: FakeOpenAI
) -> None:
    report = await speaker(tmp_path, tts_base_url=fake_openai.url, tts_voice="nova").say("Hello there")
    assert report.engine == "openai" and report.seconds == pytest.approx(0.75)
    request = fake_openai.requests[-1]
    assert request["path"] == "/v1/audio/speech"
    assert request["body"] == {
        "model": "tts-1",
        "input": "Hello there",
        "voice": "nova",
        "response_format": "wav",
    }


async def test_a_failing_cloud_engine_falls_back_to_espeak(tmp_path: Path, fake_openai: FakeOpenAI) -> None:
    fake_openai.fail_with = 503
    report = await speaker(tmp_path, tts_base_url=fake_openai.url).say("Still here")
    assert report.engine == "local"
    assert any("HTTP 503" in reason for reason in report.skipped)


async def test_groq_sends_its_key_to_its_own_endpoint(fake_openai: FakeOpenAI) -> None:
    engine = OpenAISpeechTts.groq(ReachySettings(groq_api_key="gsk-test"))
    assert engine.unavailable() is None and engine.model == "canopylabs/orpheus-v1-english"
    engine.base_url = fake_openai.url  # the real one is Groq's; the request shape is what matters
    data = await engine.synthesize("hi")
    assert wav_duration(data) == pytest.approx(0.75)
    assert fake_openai.requests[-1]["headers"]["Authorization"] == "Bearer gsk-test"


async def test_elevenlabs_pcm_is_wrapped_as_wav(
    fake_openai: FakeOpenAI, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ELEVENLABS_API_KEY", "el-test")
    engine = ElevenLabsTts(ReachySettings(), base_url=fake_openai.url)
    fake_openai.fail_with = 401
    with pytest.raises(TtsError, match="ElevenLabs answered HTTP 401"):
        await engine.synthesize("hi")
    assert fake_openai.requests[-1]["headers"]["xi-api-key"] == "el-test"
    assert fake_openai.requests[-1]["path"].startswith("/v1/text-to-speech/JBFqnCBsd6RMkjVDRZzb")


async def test_without_keys_the_cloud_engines_say_why_they_are_skipped() -> None:
    settings = ReachySettings()
    assert "ELEVENLABS_API_KEY" in (ElevenLabsTts(settings).unavailable() or "")
    assert "GROQ_API_KEY" in (OpenAISpeechTts.groq(settings).unavailable() or "")
    assert "tts_base_url" in (OpenAISpeechTts.openai_compatible(settings).unavailable() or "")


async def test_local_voice_and_rate_are_used() -> None:
    slow = await LocalTts(ReachySettings(local_rate=100, local_voice="gmw/en-us")).synthesize("one two three")
    fast = await LocalTts(ReachySettings(local_rate=300)).synthesize("one two three")
    assert wav_duration(slow) > wav_duration(fast)


async def test_without_the_espeak_command_the_library_speaks_with_each_speakers_rate(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no espeak-ng command: libespeak-ng in this process
    slow = await LocalTts(ReachySettings(local_rate=100)).synthesize("one two three")
    fast = await LocalTts(ReachySettings(local_rate=300)).synthesize("one two three")
    assert wav_duration(slow) > 1.5 * wav_duration(fast)


async def test_without_the_espeak_command_a_speakers_voice_does_not_stay_for_the_next(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    before = wav_duration(await LocalTts(ReachySettings()).synthesize("one two three"))
    german = wav_duration(await LocalTts(ReachySettings(local_voice="de")).synthesize("one two three"))
    after = wav_duration(await LocalTts(ReachySettings()).synthesize("one two three"))
    assert german > 1.05 * before  # the voice is heard: German says "one two three" more slowly
    assert after == pytest.approx(before, rel=0.01)  # and does not stay for the next speaker


async def test_without_the_espeak_command_an_unknown_voice_is_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(TtsError, match="no voice 'xx-nowhere'"):
        await LocalTts(ReachySettings(local_voice="xx-nowhere")).synthesize("hello")


async def test_asking_for_a_robot_speaker_that_is_not_there_says_so(tmp_path: Path) -> None:
    with pytest.raises(DeviceError, match="no speaker"):
        await speaker(tmp_path, audio_output="robot").say("hello")


async def test_old_speech_files_are_pruned(tmp_path: Path) -> None:
    talker = speaker(tmp_path)
    for i in range(22):
        await talker.say(f"number {i}")
    assert len(list((tmp_path / "speech").glob("*.wav"))) == 20


async def test_a_second_sentence_follows_the_first_instead_of_cutting_it(tmp_path: Path) -> None:
    talker = speaker(tmp_path)
    first = await talker.say("The lamp is on.")
    second = await talker.say("And the music is playing.")
    assert second.speaking_until == pytest.approx(first.speaking_until + second.seconds, abs=0.01)
    assert talker.last_spoken == "And the music is playing."


class SilentCard:
    """A sound card that plays nothing: the edge we do not own (PortAudio and a device)."""

    def __init__(self) -> None:
        self.played = 0
        self.stopped = 0

    def play(self, data: bytes) -> None:
        self.played += 1

    def stop(self) -> None:
        self.stopped += 1


def speaker_with_card(tmp_path: Path) -> tuple[Speaker, SilentCard]:
    config = ReachySettings.model_validate({"audio_output": "host"})
    speech = Speaker(build_engines(config), tmp_path / "speech", tmp_path, None, config.audio_output)
    card = SilentCard()
    speech._host, speech._host_checked = card, True  # type: ignore[assignment]
    return speech, card


async def test_a_stop_cuts_the_sentence_and_drops_the_one_waiting_its_turn(tmp_path: Path) -> None:
    import asyncio

    speech, card = speaker_with_card(tmp_path)
    await speech.say("This is a rather long answer that goes on for a while.")
    waiting = asyncio.create_task(speech.say("And this one waits its turn."))
    for _ in range(500):  # until the second is synthesized (its file written) and waits its turn
        if len(list((tmp_path / "speech").glob("*.wav"))) == 2:
            break
        await asyncio.sleep(0.01)
    await asyncio.sleep(0.05)
    stopped = await speech.stop()
    report = await asyncio.wait_for(waiting, 2.0)
    assert stopped.stopped and stopped.cut_off == "This is a rather long answer that goes on for a while."
    assert report.interrupted is True and card.played == 1 and card.stopped == 1
    assert speech.speaking is False and speech.last_spoken.startswith("This is a rather long")


async def test_interrupt_says_the_new_sentence_at_once(tmp_path: Path) -> None:
    speech, card = speaker_with_card(tmp_path)
    first = await speech.say("This is a rather long answer that goes on for a while.")
    began = time.monotonic()
    second = await speech.say("Stop.", interrupt=True)
    assert time.monotonic() - began < first.seconds / 2  # it did not wait for the first to end
    assert second.cut_off == first.spoken and not second.interrupted and card.played == 2
    assert speech.last_spoken == "Stop."
