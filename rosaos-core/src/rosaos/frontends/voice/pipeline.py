"""The voice pipeline: audio → VAD → STT → wake → ``POST /stt``, reporting each step as it goes.

Reading audio and understanding it run as two tasks joined by a queue, so a slow transcription
never makes the microphone drop audio; utterances are still handled one at a time, in order,
because the follow-up window depends on what came before.

While the robot speaks, a live source's audio goes to :class:`~rosaos.frontends.voice.bargein.BargeIn`
instead of the segmenter: when the user talks over the robot, the robot stops speaking, listening
resumes at once (with the audio since just before the user began), and what they say is a new
utterance like any other, within the follow-up window.
"""

from __future__ import annotations

import asyncio
import hashlib
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

import numpy as np

from rosaos.frontends.voice.bargein import BargeIn
from rosaos.frontends.voice.early import EarlyTranscriber
from rosaos.frontends.voice.end_of_turn import TurnJudge, is_whole_command
from rosaos.frontends.voice.replies import ReplyFollower
from rosaos.frontends.voice.robot import NoRobot, RobotLink
from rosaos.frontends.voice.sources import (
    SAMPLE_RATE,
    AudioChunk,
    AudioSource,
    FrameSource,
    VoiceError,
)
from rosaos.frontends.voice.stt import SpeechToText
from rosaos.frontends.voice.vad import Segmenter, SpeechSegment
from rosaos.frontends.voice.wake import EyeContact, WakeGate, is_noise
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

HeardKind = Literal[
    "ready",
    "speech",
    "draft",
    "transcript",
    "woke",
    "sent",
    "reply",
    "ignored",
    "dropped",
    "muted",
    "barge_in",
    "notice",
    "error",
    "done",
]
RETRY_DELAYS = (0.5, 1.0, 2.0)
"""Seconds between attempts to reach the kernel; the idempotency key makes retries safe."""


@dataclass(frozen=True)
class Heard:
    """One step the pipeline reports: a line for people, a JSON object with ``--json``."""

    kind: HeardKind
    text: str = ""
    data: dict[str, Any] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "text": self.text, **self.data}


Reporter = Callable[[Heard], None]


def idempotency_key(source: str, wall_start: float) -> str:
    """The same utterance of the same source always gets the same key, so a retried POST is one event.

    ``wall_start`` is rounded to the millisecond: retries reuse the segment's own value, never a
    recomputed one, so rounding only has to be stable, not precise.
    """
    digest = hashlib.sha256(f"{source}|{wall_start:.3f}".encode()).hexdigest()
    return f"voice-{digest[:32]}"


class Handoff(Protocol):
    """Where commands go: the kernel's ``POST /stt`` (tests may collect them instead)."""

    async def send(self, text: str, key: str) -> dict[str, Any]:
        """Send one command; returns the kernel's answer ``{"id", "duplicate"}``."""
        ...


class KernelHandoff:
    """``POST /stt`` with retries: a kernel that restarts meanwhile still gets every command once."""

    def __init__(self, client: KernelClient, delays: tuple[float, ...] = RETRY_DELAYS) -> None:
        self.client = client
        self.delays = delays

    async def send(self, text: str, key: str) -> dict[str, Any]:
        for delay in (*self.delays, None):
            try:
                answer: dict[str, Any] = await self.client.request(
                    "POST", "/stt", json={"text": text, "idempotency_key": key}
                )
                return answer
            except KernelUnavailable as error:
                if delay is None or " failed with 4" in str(error):  # a 4xx will not heal by retrying
                    raise
                await asyncio.sleep(delay)
        raise AssertionError("unreachable")


@dataclass
class PipelineStats:
    """What one run did; ``rosaos voice --wav`` exits non-zero on ``failed`` or ``errors``."""

    utterances: int = 0
    sent: int = 0
    ignored: int = 0
    dropped: int = 0
    failed: int = 0
    """Commands the kernel could not be given (after retries)."""
    errors: int = 0
    """Utterances that could not be transcribed."""
    interruptions: int = 0
    """Times the user talked over the robot and it stopped to listen (barge-in)."""


class VoicePipeline:
    """Runs one audio source through VAD, STT and wake, and hands commands to the kernel."""

    def __init__(
        self,
        source: AudioSource,
        segmenter: Segmenter,
        stt: SpeechToText,
        gate: WakeGate,
        handoff: Handoff,
        report: Reporter,
        *,
        chunk_seconds: float = 0.032,
        robot: RobotLink | None = None,
        camera: FrameSource | None = None,
        eye_contact: EyeContact | None = None,
        replies: ReplyFollower | None = None,
        reply_wait_seconds: float = 60.0,
        barge_in: BargeIn | None = None,
        early_transcription: bool = False,
        judge: TurnJudge | None = None,
    ) -> None:
        self.source = source
        self.segmenter = segmenter
        self.stt = stt
        self.gate = gate
        self.handoff = handoff
        self.report = report
        self.chunk_samples = max(1, round(chunk_seconds * SAMPLE_RATE))
        self.robot = robot or NoRobot()
        self.camera = camera
        self.eye_contact = eye_contact
        self.replies = replies
        self.reply_wait_seconds = reply_wait_seconds
        self.barge_in = barge_in
        self.transcriber = EarlyTranscriber(stt, early=early_transcription)
        if early_transcription:
            segmenter.drafts = True  # the drafts early transcription starts from
        self.judge = judge if early_transcription else None
        """Ends a turn after a short pause when its draft is a whole command (rosaos.frontends.voice.end_of_turn)."""
        self._utterances: asyncio.Queue[SpeechSegment | None] = asyncio.Queue()
        self.stats = PipelineStats()
        self._background: set[asyncio.Task[Any]] = set()
        self._t0 = time.monotonic()

    async def run(self) -> PipelineStats:
        """Listen until the source ends (a file) or the task is cancelled (a microphone).

        A file's run ends once the replies to its commands have been said (or after
        ``reply_wait_seconds``); a microphone speaks replies as they come.
        """
        self._t0 = time.monotonic()
        if self.replies is not None:
            await self.replies.start()
        utterances = self._utterances = asyncio.Queue()
        understand = asyncio.create_task(self._understand(utterances), name="voice: understand")
        helpers = []
        if self.source.live:
            helpers.append(asyncio.create_task(self.robot.follow(), name="voice: robot speaking"))
            if self.replies is not None:
                helpers.append(asyncio.create_task(self.replies.run(), name="voice: replies"))
        if self.camera is not None and self.eye_contact is not None:
            helpers.append(
                asyncio.create_task(self._watch(self.camera, self.eye_contact), name="voice: eyes")
            )
        try:
            async for segment in self._segments():
                if understand.done():  # it failed: stop reading and raise its error below
                    break
                utterances.put_nowait(segment)
            utterances.put_nowait(None)
            await understand
            if not self.source.live:
                await self._wait_for_replies()
        finally:
            for task in (understand, *helpers):
                task.cancel()
            await asyncio.gather(understand, *helpers, return_exceptions=True)
            self.transcriber.close()
            if self._background:
                await asyncio.gather(*self._background, return_exceptions=True)
        return self.stats

    async def _wait_for_replies(self) -> None:
        """A file's run ends once the replies to its commands are said, or after a while."""
        if self.replies is None or await self.replies.settle(self.reply_wait_seconds):
            return
        self.report(
            Heard(
                "notice",
                f"no final reply within {self.reply_wait_seconds:g} s; the kernel may still be working "
                "on it (rosaos ps shows its processes)",
            )
        )

    async def _segments(self) -> AsyncIterator[SpeechSegment]:
        muted = False
        read = self.chunk_samples
        if self.source.live and self.barge_in is not None:
            # The echo gate hears each VAD frame as it arrives, not a chunk later: a barge-in must
            # stop the robot within 300 ms. The segmenter still gets whole chunks.
            read = min(read, self.barge_in.classifier.frame_samples)
        pieces: list[AudioChunk] = []
        async for chunk in self.source.chunks(read):
            if self.source.live and self.robot.muted(chunk.wall):
                if not muted:  # the robot's own voice: drop it, and whatever was half-heard
                    muted = True
                    pieces.clear()
                    self.segmenter.reset()
                    if self.barge_in is not None:
                        self.barge_in.start()
                    self.report(Heard("muted", "the robot is speaking; not listening"))
                if self.barge_in is None or not self.barge_in.feed(chunk):
                    continue
                muted = False
                for segment in self._finals(self._barged_in(self.barge_in, chunk)):
                    yield self._announce(segment)
                continue
            muted = False
            pieces.append(chunk)
            if sum(piece.samples.size for piece in pieces) < self.chunk_samples:
                continue
            for segment in self._finals(self.segmenter.feed(_joined(pieces))):
                yield self._announce(segment)
            pieces.clear()
        if pieces:
            for segment in self._finals(self.segmenter.feed(_joined(pieces))):
                yield self._announce(segment)
        for segment in self.segmenter.flush():
            yield self._announce(segment)

    def _finals(self, segments: list[SpeechSegment]) -> list[SpeechSegment]:
        """Start transcribing the drafts among ``segments`` at once; return the final ones."""
        for segment in segments:
            if segment.draft:
                self.transcriber.draft(segment)
                if self.judge is not None:
                    self._in_background(self._judge_draft(segment, self.judge))
        return [segment for segment in segments if not segment.draft]

    async def _judge_draft(self, draft: SpeechSegment, judge: TurnJudge) -> None:
        """A draft that is a whole command ends its turn after the short pause, not the long one.

        Each draft's transcript is reported (``--json`` only) with when each step finished, in
        stream seconds, so a turn that still waited the long pause says why: the transcript came
        too late to judge (``whole`` null), the judge was slow, or it was not a whole command.
        """
        result = await self.transcriber.of_draft(draft)
        transcribed = self.segmenter.now
        if result is None:
            return  # replaced by a newer draft, or it failed (the final utterance retries it)
        # Not held: the speaker went on, or the long pause ended the turn before the transcript came.
        held = self.segmenter.holds(draft)
        whole = await is_whole_command(judge, result.text, self.gate.phrases) if held else None
        judged = self.segmenter.now
        final = self.segmenter.complete(draft) if whole else None  # None: feed() ends it later
        self.report(
            Heard(
                "draft",
                result.text,
                {
                    **_times(draft),
                    "drafted_at": draft.detected_at,
                    "transcribed_at": round(transcribed, 3),
                    "judged_at": round(judged, 3),
                    "stt_seconds": result.compute_seconds,
                    "whole": whole,
                },
            )
        )
        if final is not None:
            self._utterances.put_nowait(self._announce(final))

    def _barged_in(self, barge_in: BargeIn, chunk: AudioChunk) -> list[SpeechSegment]:
        """The user talks over the robot: stop it, listen from just before they began."""
        self.stats.interruptions += 1
        self.robot.unmute()
        self._in_background(self.robot.stop_speaking())
        onset = barge_in.onset if barge_in.onset is not None else chunk.start
        # Talking over the robot is talking to it: what they say needs no wake phrase.
        self.gate.open(onset)
        self.report(
            Heard(
                "barge_in",
                "the user spoke over the robot; it stops to listen",
                {"onset": round(onset, 3), "at": round(chunk.start + chunk.samples.size / SAMPLE_RATE, 3)},
            )
        )
        self.segmenter.reset()
        return [segment for kept in barge_in.take() for segment in self.segmenter.feed(kept)]

    def _announce(self, segment: SpeechSegment) -> SpeechSegment:
        self.stats.utterances += 1
        self.report(Heard("speech", "", _times(segment)))
        return segment

    async def _understand(self, utterances: asyncio.Queue[SpeechSegment | None]) -> None:
        while (segment := await utterances.get()) is not None:
            try:
                await self.handle(segment)
            except VoiceError as error:
                self.stats.errors += 1
                self.report(Heard("error", str(error), _times(segment)))

    async def handle(self, segment: SpeechSegment) -> None:
        """Transcribe one utterance, decide, and send the command (or say why not)."""
        began = time.perf_counter()
        result = await self.transcriber.transcribe(segment)
        transcript = result.text
        times = {
            **_times(segment),
            "stt_seconds": result.compute_seconds,
            "stt_wait_seconds": round(time.perf_counter() - began, 3),
            "early": result.early,
        }
        self.report(Heard("transcript", transcript, times))
        if is_noise(transcript):
            self.stats.dropped += 1
            self.report(Heard("dropped", transcript, {**times, "reason": "no words"}))
            return
        decision = self.gate.decide(transcript, segment.start, segment.end)
        if decision.woke:
            self._in_background(self.robot.woke(segment.doa, self.gate.awake_until - segment.end))
        if decision.action == "woke":
            self.report(Heard("woke", decision.reason, {**times, "awake_until": self.gate.awake_until}))
            return
        if decision.action == "ignored":
            self.stats.ignored += 1
            self.report(Heard("ignored", transcript, {**times, "reason": decision.reason}))
            return
        if is_noise(decision.command):
            self.stats.dropped += 1
            self.report(Heard("dropped", decision.command, {**times, "reason": "no words"}))
            return
        key = idempotency_key(self.source.name, segment.wall_start)
        posted = time.perf_counter()
        try:
            answer = await self.handoff.send(decision.command, key)
        except KernelUnavailable as error:
            self.stats.failed += 1
            self.report(Heard("error", str(error), {**times, "idempotency_key": key}))
            return
        self.stats.sent += 1
        self._in_background(self.robot.listened())
        if self.replies is not None and not answer.get("duplicate"):
            self.replies.follow(int(answer["id"]))
        data = {
            **times,
            "event_id": answer.get("id"),
            "duplicate": answer.get("duplicate", False),
            "idempotency_key": key,
            "reason": decision.reason,
            "post_seconds": round(time.perf_counter() - posted, 3),
            "sent_at": time.time(),
        }
        self.report(Heard("sent", decision.command, data))

    async def _watch(self, camera: FrameSource, eyes: EyeContact) -> None:
        """Eye-contact wake: a face held on the camera opens the follow-up window."""
        async for frame in camera.frames():
            if not await asyncio.to_thread(eyes.observe, frame):
                continue
            if self.gate.open(time.monotonic() - self._t0):
                self.report(Heard("woke", "eye contact", {"awake_until": self.gate.awake_until}))
                self._in_background(self.robot.woke(None, self.gate.follow_up_seconds))

    def _in_background(self, work: Any) -> None:
        task = asyncio.ensure_future(work)
        self._background.add(task)
        task.add_done_callback(self._background.discard)


def _joined(pieces: list[AudioChunk]) -> AudioChunk:
    """Consecutive pieces of audio as one chunk (the last direction of arrival given, if any)."""
    if len(pieces) == 1:
        return pieces[0]
    doa = next((piece.doa for piece in reversed(pieces) if piece.doa is not None), None)
    samples = np.concatenate([piece.samples for piece in pieces])
    return AudioChunk(samples, pieces[0].start, pieces[0].wall, doa)


def _times(segment: SpeechSegment) -> dict[str, Any]:
    return {
        "start": segment.start,
        "end": segment.end,
        "vad_delay": round(segment.vad_delay, 3),
        "doa": segment.doa,
    }
