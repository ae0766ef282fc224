"""The pipeline: what is sent to the kernel, what is not, with which key; and the robot's own voice."""

from __future__ import annotations

from collections.abc import AsyncIterator
from typing import Any

import numpy as np
import pytest

from rosaos.frontends.voice.pipeline import Heard, KernelHandoff, VoicePipeline, idempotency_key
from rosaos.frontends.voice.sources import SAMPLE_RATE, AudioChunk, Samples, VoiceError
from rosaos.frontends.voice.vad import EnergyClassifier, Segmenter
from rosaos.frontends.voice.wake import WakeGate
from rosaos.kernel.api.kernel_client import KernelUnavailable

from .voice_support import pattern


def test_the_idempotency_key_is_stable_for_the_same_utterance() -> None:
    assert idempotency_key("mic", 1_700_000_000.1234) == idempotency_key("mic", 1_700_000_000.1234)
    assert idempotency_key("mic", 1_700_000_000.1234).startswith("voice-")


def test_the_idempotency_key_differs_by_source_and_by_start() -> None:
    keys = {
        idempotency_key("mic", 1_700_000_000.0),
        idempotency_key("reachy", 1_700_000_000.0),
        idempotency_key("mic", 1_700_000_000.5),
    }
    assert len(keys) == 3


def test_the_idempotency_key_fits_the_kernel_limit() -> None:
    assert len(idempotency_key("wav:/" + "x" * 500, 0.0)) <= 200


class ToneSource:
    """Tones as utterances (the energy VAD hears them); ``live`` sources get echo suppression."""

    name = "test"

    def __init__(self, samples: Samples, live: bool = False) -> None:
        self.samples = samples
        self.live = live

    async def chunks(self, chunk_samples: int) -> AsyncIterator[AudioChunk]:
        for i in range(0, self.samples.size, chunk_samples):
            yield AudioChunk(self.samples[i : i + chunk_samples], i / SAMPLE_RATE, 5_000.0 + i / SAMPLE_RATE)


class ScriptedSTT:
    """Returns the next scripted transcript for each utterance."""

    name = "scripted"

    def __init__(self, *transcripts: str) -> None:
        self.transcripts = list(transcripts)

    async def transcribe(self, samples: Samples) -> str:
        return self.transcripts.pop(0)


class Collected:
    def __init__(self) -> None:
        self.sent: list[tuple[str, str]] = []

    async def send(self, text: str, key: str) -> dict[str, Any]:
        self.sent.append((text, key))
        return {"id": len(self.sent), "duplicate": False}


async def run(
    transcripts: list[str], bursts: int | None = None, **pipeline: Any
) -> tuple[Collected, list[Heard]]:
    count = len(transcripts) if bursts is None else bursts
    audio = pattern(*[("tone", 0.6), ("silence", 1.0)] * count)
    sink, heard = Collected(), []
    voice = VoicePipeline(
        pipeline.pop("source", ToneSource(audio)),
        Segmenter(EnergyClassifier()),
        ScriptedSTT(*transcripts),
        pipeline.pop("gate", WakeGate(phrase="hello")),
        sink,
        heard.append,
        **pipeline,
    )
    await voice.run()
    return sink, heard


async def test_a_wake_and_command_is_sent_without_the_wake_phrase() -> None:
    sink, heard = await run(["Hello. Turn on the kitchen light."])
    assert [text for text, _ in sink.sent] == ["Turn on the kitchen light."]
    sent = next(h for h in heard if h.kind == "sent")
    assert sent.data["event_id"] == 1 and sent.data["idempotency_key"] == sink.sent[0][1]
    assert sent.data["vad_delay"] > 0.5 and "stt_seconds" in sent.data


async def test_empty_and_noise_transcripts_are_dropped_not_sent() -> None:
    sink, heard = await run(["", "[BLANK_AUDIO]", "Um."], gate=WakeGate(mode="off"))
    assert sink.sent == []
    assert [h.kind for h in heard].count("dropped") == 3


async def test_a_wake_phrase_alone_is_not_sent_but_opens_the_window() -> None:
    sink, heard = await run(["Hello.", "Turn on the kitchen light."])
    assert [text for text, _ in sink.sent] == ["Turn on the kitchen light."]
    assert [h.kind for h in heard if h.kind in ("woke", "sent")] == ["woke", "sent"]


async def test_speech_without_the_wake_phrase_is_ignored() -> None:
    sink, heard = await run(["Turn on the kitchen light."])
    assert sink.sent == []
    assert any(h.kind == "ignored" for h in heard)


async def test_every_utterance_gets_its_own_key() -> None:
    sink, _ = await run(["Hello, lights on.", "And the lamp.", "Thanks."])
    assert len({key for _, key in sink.sent}) == 3


async def test_a_failed_transcription_is_reported_and_listening_goes_on() -> None:
    class Failing(ScriptedSTT):
        async def transcribe(self, samples: Samples) -> str:
            text = await super().transcribe(samples)
            if text == "boom":
                raise VoiceError("the engine fell over")
            return text

    sink, heard = Collected(), []
    audio = pattern(("tone", 0.6), ("silence", 1.0), ("tone", 0.6), ("silence", 1.0))
    pipeline = VoicePipeline(
        ToneSource(audio),
        Segmenter(EnergyClassifier()),
        Failing("boom", "Hello, lights on."),
        WakeGate(),
        sink,
        heard.append,
    )
    stats = await pipeline.run()
    assert (stats.errors, stats.sent) == (1, 1)
    assert any(h.kind == "error" and "fell over" in h.text for h in heard)


class Speaking:
    """A robot that speaks from wall time 5000.0 to 5001.2 (the first burst and a bit)."""

    def __init__(self) -> None:
        self.woken: list[float | None] = []
        self.listened_to = 0

    async def woke(self, doa: float | None, seconds: float) -> None:
        assert seconds > 0
        self.woken.append(doa)

    async def listened(self) -> None:
        self.listened_to += 1

    def muted(self, wall: float) -> bool:
        return 5_000.0 <= wall < 5_001.2

    async def follow(self) -> None:
        return None


async def test_while_the_robot_speaks_a_live_source_is_not_heard() -> None:
    audio = pattern(("tone", 0.6), ("silence", 1.0), ("tone", 0.6), ("silence", 1.0))
    robot = Speaking()
    sink, heard = await run(["Hello, lights on."], bursts=2, source=ToneSource(audio, live=True), robot=robot)
    assert [text for text, _ in sink.sent] == ["lights on."]
    assert any(h.kind == "muted" for h in heard)
    assert robot.woken == [None] and robot.listened_to == 1  # listening from the wake to the command


class FlakyClient:
    """A kernel that is down for the first ``failures`` requests."""

    def __init__(self, failures: int, error: str = "cannot reach the rosaOS kernel") -> None:
        self.failures = failures
        self.error = error
        self.bodies: list[dict[str, Any]] = []

    async def request(self, method: str, path: str, **kwargs: Any) -> Any:
        self.bodies.append(kwargs["json"])
        if len(self.bodies) <= self.failures:
            raise KernelUnavailable(self.error)
        return {"id": 7, "duplicate": len(self.bodies) > 1}


async def test_the_handoff_retries_with_the_same_key() -> None:
    client = FlakyClient(failures=2)
    answer = await KernelHandoff(client, delays=(0, 0, 0)).send("lights on", "voice-abc")  # type: ignore[arg-type]
    assert answer["id"] == 7
    assert [b["idempotency_key"] for b in client.bodies] == ["voice-abc"] * 3


async def test_the_handoff_gives_up_after_its_retries() -> None:
    client = FlakyClient(failures=10)
    with pytest.raises(KernelUnavailable):
        await KernelHandoff(client, delays=(0, 0)).send("lights on", "k")  # type: ignore[arg-type]
    assert len(client.bodies) == 3


async def test_a_refused_request_is_not_retried() -> None:
    client = FlakyClient(failures=10, error="POST /stt failed with 422: invalid request")
    with pytest.raises(KernelUnavailable):
        await KernelHandoff(client, delays=(0, 0)).send("lights on", "k")  # type: ignore[arg-type]
    assert len(client.bodies) == 1


def test_heard_as_json_is_flat() -> None:
    assert Heard("sent", "hi", {"event_id": 3}).as_json() == {"kind": "sent", "text": "hi", "event_id": 3}


def test_chunks_are_sized_from_the_chunk_seconds() -> None:
    pipeline = VoicePipeline(
        ToneSource(np.zeros(1, np.float32)),
        Segmenter(EnergyClassifier()),
        ScriptedSTT(),
        WakeGate(),
        Collected(),
        print,
        chunk_seconds=0.12,
    )
    assert pipeline.chunk_samples == 1920


class SpeakingUntilStopped:
    """A robot that talks until the pipeline stops it (barge-in)."""

    def __init__(self) -> None:
        self.talking = True
        self.stops = 0

    async def woke(self, doa: float | None, seconds: float) -> None:
        return None

    async def listened(self) -> None:
        return None

    def muted(self, wall: float) -> bool:
        return self.talking

    def unmute(self) -> None:
        self.talking = False

    async def stop_speaking(self) -> bool:
        self.stops += 1
        return True

    async def follow(self) -> None:
        return None


class SizedToneSource(ToneSource):
    def __init__(self, samples: Samples) -> None:
        super().__init__(samples, live=True)
        self.asked: list[int] = []

    async def chunks(self, chunk_samples: int) -> AsyncIterator[AudioChunk]:
        self.asked.append(chunk_samples)
        async for chunk in super().chunks(chunk_samples):
            yield chunk


async def test_a_barge_in_is_heard_frame_by_frame_and_the_segmenter_still_gets_whole_chunks() -> None:
    from rosaos.frontends.voice.bargein import BargeIn

    classifier = EnergyClassifier()
    audio = pattern(("silence", 0.5), ("tone", 0.8), ("silence", 1.0))
    source, robot = SizedToneSource(audio), SpeakingUntilStopped()
    segmenter = Segmenter(classifier)
    fed: list[int] = []
    feed = segmenter.feed
    segmenter.feed = lambda chunk: (fed.append(chunk.samples.size), feed(chunk))[1]  # type: ignore[method-assign]
    heard: list[Heard] = []
    pipeline = VoicePipeline(
        source, segmenter, ScriptedSTT("stop"), WakeGate(), Collected(), heard.append,
        robot=robot, barge_in=BargeIn(classifier), chunk_seconds=0.12,
    )  # fmt: skip
    stats = await pipeline.run()
    assert source.asked == [classifier.frame_samples]  # read frame by frame while the robot may speak
    [barge] = [h for h in heard if h.kind == "barge_in"]
    assert barge.data["at"] - barge.data["onset"] < 0.12 + 2 * 0.03  # not a whole chunk late
    assert robot.stops == 1 and stats.interruptions == 1 and stats.sent == 1
    chunk = round(0.12 * SAMPLE_RATE)
    # The kept audio goes in as it was read; once the robot is silent, whole chunks again.
    assert fed[-2] >= chunk, fed
