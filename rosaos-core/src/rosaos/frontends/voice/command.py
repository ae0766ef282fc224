"""``rosaos voice``: listen, transcribe, hand commands to the running kernel, say its replies.

With ``--wav`` it exits once the file is processed, every command handed off, and the kernel's
replies to them said (or after a minute without a final reply). A microphone runs until Ctrl-C.

Exit codes: 0 when every command was handed off; 1 when the audio, VAD or STT fails (the message
says what to install); 2 when the configuration is bad or the kernel cannot be reached.
"""

from __future__ import annotations

import asyncio
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any, Literal

from rosaos.auth import token_path
from rosaos.cli.console import console as terminal
from rosaos.config import ConfigError, RosaosConfig, VoiceConfig, load_config
from rosaos.frontends.voice.bargein import BargeIn, BargeInSettings
from rosaos.frontends.voice.end_of_turn import KernelJudge
from rosaos.frontends.voice.pipeline import Heard, KernelHandoff, PipelineStats, VoicePipeline
from rosaos.frontends.voice.replies import ReplyFollower
from rosaos.frontends.voice.robot import find_reachy
from rosaos.frontends.voice.sources import (
    AudioSource,
    FrameSource,
    MicSource,
    ReachyCamera,
    ReachySource,
    VoiceError,
    WavSource,
    open_reachy_media,
    require_media,
)
from rosaos.frontends.voice.stt import MoonshineSTT, OpenAITranscriptionSTT, build_stt
from rosaos.frontends.voice.vad import EnergyClassifier, FrameClassifier, Segmenter, SileroClassifier
from rosaos.frontends.voice.wake import EyeContact, HaarFaceDetector, WakeGate
from rosaos.frontends.voice.word_bias import world_phrases
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_UNAVAILABLE = 2

_STYLE = {"sent": "bold green", "error": "bold red", "woke": "cyan", "ignored": "dim", "dropped": "dim"}


def voice_command(
    config_path: Path | None,
    wav: Path | None,
    source: Literal["mic", "reachy"] | None,
    url: str | None,
    json_output: bool,
) -> int:
    """Entry point for the CLI: build the pipeline, run it, map failures to exit codes."""
    try:
        config = load_config(config_path)
    except ConfigError as error:
        return _fail(str(error), EXIT_UNAVAILABLE)
    try:
        return asyncio.run(_run(config, wav, source, url, json_output))
    except KernelUnavailable as error:
        return _fail(str(error), EXIT_UNAVAILABLE)
    except VoiceError as error:
        return _fail(str(error), EXIT_FAILED)


async def _run(
    config: RosaosConfig,
    wav: Path | None,
    source_name: Literal["mic", "reachy"] | None,
    url: str | None,
    json_output: bool,
) -> int:
    voice = config.voice
    closers: list[Any] = []
    try:
        source = _source(voice, wav, source_name, closers)  # a bad WAV file is the first thing to report
        async with KernelClient.from_config(config, url=url) as client:
            await client.health()  # fail now, not after the first sentence, if the kernel is not there
            token = token_path(config.data_dir).read_text(encoding="utf-8").strip()
            camera = _camera(voice, source, closers)
            stt = build_stt(voice)
            if isinstance(stt, OpenAITranscriptionSTT):
                closers.append(stt.aclose)
            names = await _world_phrases(config, client)
            if isinstance(stt, MoonshineSTT) and voice.vocabulary_bias:
                stt.bias_toward([*names, voice.wake_phrase, *voice.wake_aliases])
            robot = await find_reachy(client, token)
            report = _printer(json_output)
            replies = ReplyFollower(client, robot, _reply_reporter(report)) if voice.speak_replies else None
            segmenter = Segmenter(
                _classifier(voice),
                silence_seconds=voice.silence_seconds,
                min_speech_seconds=voice.min_speech_seconds,
                max_utterance_seconds=voice.max_utterance_seconds,
                complete_silence_seconds=voice.complete_silence_seconds,
            )
            pipeline = VoicePipeline(
                source,
                segmenter,
                stt,
                _gate(voice, camera is not None),
                KernelHandoff(client),
                report,
                chunk_seconds=voice.chunk_seconds,
                robot=robot,
                camera=camera,
                eye_contact=EyeContact(HaarFaceDetector(), voice.eye_contact_frames) if camera else None,
                replies=replies,
                barge_in=_barge_in(voice, segmenter),
                early_transcription=voice.early_transcription and voice.stt == "local",
                judge=KernelJudge(client, names),
            )
            pipeline.report(
                Heard("ready", _describe(voice, source, pipeline, client), {"kernel": client.base_url})
            )
            stats = await pipeline.run()
            pipeline.report(Heard("done", _tally(stats), dataclasses.asdict(stats)))
    finally:
        for close in closers:
            result = close()
            if asyncio.iscoroutine(result):
                await result
    return _exit_code(stats)


async def _world_phrases(config: RosaosConfig, client: KernelClient) -> list[str]:
    """The words of the kernel's world (its devices, even when this rosaos.toml has none) and of
    this configuration's device tables (aliases, rooms, catalogs)."""
    devices: dict[str, Any] = {name: device.model_dump() for name, device in config.devices.items()}
    try:
        for device in await client.request("GET", "/devices") or []:
            devices.setdefault(str(device["name"]), device)
    except KernelUnavailable:
        pass  # the config's devices only
    return world_phrases(devices)


def _source(
    voice: VoiceConfig, wav: Path | None, name: Literal["mic", "reachy"] | None, closers: list[Any]
) -> AudioSource:
    if wav is not None:
        return WavSource(wav)
    if (name or voice.source) == "mic":
        return MicSource()
    media, close = open_reachy_media(voice.reachy_host, voice.reachy_port)
    closers.append(close)
    require_media(media, "audio", "use --source mic")
    return ReachySource(media)


def _camera(voice: VoiceConfig, source: AudioSource, closers: list[Any]) -> FrameSource | None:
    """The Reachy camera for eye-contact wake, or None when the phrase alone wakes the robot."""
    if voice.wake not in ("eye_contact", "either"):
        return None
    if isinstance(source, WavSource):
        if voice.wake == "eye_contact":
            raise VoiceError(
                "wake = 'eye_contact' needs the robot's camera, which --wav has not: set wake = 'phrase'"
            )
        return None
    media = source.media if isinstance(source, ReachySource) else None
    try:
        if media is None:
            media, close = open_reachy_media(voice.reachy_host, voice.reachy_port)
            closers.append(close)
        require_media(media, "camera", "eye-contact wake is not available; set [voice] wake = 'phrase'")
    except VoiceError as error:
        if voice.wake == "eye_contact":
            raise
        print(f"rosaos voice: {error}; waking on the phrase only", file=sys.stderr)
        return None
    return ReachyCamera(media)


def _classifier(voice: VoiceConfig) -> FrameClassifier:
    if voice.vad == "energy":
        return EnergyClassifier(voice.energy_threshold_db)
    return SileroClassifier(voice.vad_threshold)


def _barge_in(voice: VoiceConfig, segmenter: Segmenter) -> BargeIn | None:
    """Barge-in shares the segmenter's VAD: one listens while the robot speaks, the other otherwise."""
    if not voice.barge_in:
        return None
    settings = BargeInSettings(
        margin_db=voice.barge_in_margin_db, min_speech_seconds=voice.barge_in_min_seconds
    )
    return BargeIn(segmenter.classifier, settings)


def _gate(voice: VoiceConfig, has_camera: bool) -> WakeGate:
    mode = voice.wake
    if mode == "either" and not has_camera:
        mode = "phrase"
    return WakeGate(mode, voice.wake_phrase, voice.wake_aliases, voice.follow_up_seconds)


def _describe(voice: VoiceConfig, source: AudioSource, pipeline: VoicePipeline, client: KernelClient) -> str:
    wake = {
        "phrase": f"wake phrase {voice.wake_phrase!r}",
        "eye_contact": "eye contact",
        "either": f"wake phrase {voice.wake_phrase!r} or eye contact",
        "off": "no wake needed",
    }[pipeline.gate.mode]
    return (
        f"listening to {source.name} (vad {voice.vad}, stt {pipeline.stt.name}, {wake}) "
        f"for the kernel at {client.base_url}"
    )


def _printer(json_output: bool) -> Any:
    if json_output:

        def print_json(heard: Heard) -> None:
            print(json.dumps(heard.as_json(), default=str), flush=True)

        return print_json
    console = terminal()

    def print_line(heard: Heard) -> None:
        line = _line(heard)
        if line:
            console.print(line, style=_STYLE.get(heard.kind), markup=False, highlight=False)

    return print_line


def _line(heard: Heard) -> str | None:
    """The line a person sees for one step; None for steps only ``--json`` shows."""
    data = heard.data
    if heard.kind == "ready":
        return f"rosaos voice: {heard.text}"
    if heard.kind == "transcript":
        return (
            f"heard {heard.text!r} ({data['start']:.2f}-{data['end']:.2f} s, stt {data['stt_seconds']:.2f} s)"
        )
    if heard.kind == "sent":
        duplicate = " (duplicate: already sent)" if data.get("duplicate") else ""
        return f"  → sent {heard.text!r} to the kernel as event {data['event_id']}{duplicate}"
    if heard.kind == "reply":
        said = "the robot says" if data.get("spoken") else "rosaos"
        return f"  {said}: {heard.text}"
    if heard.kind == "woke":
        return f"  awake ({heard.text}): listening without the wake phrase until {data['awake_until']:.1f} s"
    if heard.kind in ("ignored", "dropped"):
        return f"  {heard.kind}: {data.get('reason', '')}"
    if heard.kind == "error":
        return f"  error: {heard.text}"
    if heard.kind in ("muted", "notice", "barge_in"):
        return f"  {heard.text}"
    if heard.kind == "done":
        return f"done: {heard.text}"
    return None


def _reply_reporter(report: Any) -> Any:
    def on_reply(event_id: int, text: str, spoken: bool) -> None:
        report(Heard("reply", text, {"event_id": event_id, "spoken": spoken}))

    return on_reply


def _tally(stats: PipelineStats) -> str:
    counts = dataclasses.asdict(stats)
    return ", ".join(f"{name} {value}" for name, value in counts.items() if value or name == "sent")


def _exit_code(stats: PipelineStats) -> int:
    if stats.failed:
        return EXIT_UNAVAILABLE
    return EXIT_FAILED if stats.errors else EXIT_OK


def _fail(message: str, code: int) -> int:
    print(f"rosaos voice: {message}", file=sys.stderr)
    return code
