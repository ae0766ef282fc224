"""How often end of turn by meaning would cut a sentence at a pause: false early ends.

A turn ends after 0.18 s of silence when its draft is a whole command
(:mod:`rosaos.frontends.voice.end_of_turn`). If the speaker pauses mid-sentence ("turn on the …
kitchen light") for that long, the draft at the pause is judged too, and a false "whole" would send
half a command. So every public one-sentence task is cut after each of its words but the last, and
each beginning is judged as a draft would be:

- **spoken**: espeak-ng says the beginning alone, Moonshine transcribes it padded with the
  post-roll's zeros (what a draft holds), biased toward the task's world; the offline engine of
  that world judges the transcript;
- **written**: the engine judges the beginning's own words (no recognition errors).

A **false early end** is a beginning judged whole whose command, as the engine reads it, is not the
whole sentence's (a beginning that already means the same, "turn on the kitchen light" of "...
please", is no harm). Both the engine alone (``is_exact``, as before issue 25's third sitting) and the judge the
voice front end now uses are counted, so the rules' effect is in every run: a draft ending on
"the", "to", "and", ..., or partway into one of the world's names, is never whole, and neither is
a command that would set a robot moving.
Also: the share of whole sentences judged whole, i.e. the turns that end by meaning at all.

Run alone: ``.venv/bin/python benchmarks/voice_turns.py``; ``voice.py`` runs it too.
"""

from __future__ import annotations

import argparse
import asyncio
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from voice_accuracy import command_reader, public_sentences

from rosaos.frontends.voice.end_of_turn import EngineJudge, command_of, is_whole_command
from rosaos.frontends.voice.sources import SAMPLE_RATE, read_wav
from rosaos.frontends.voice.stt import MoonshineSTT
from rosaos.frontends.voice.vad import POST_ROLL_SECONDS
from rosaos.frontends.voice.word_bias import world_phrases

WAKE = ["hello"]


def _matcher(world: dict[str, Any]) -> Any:
    from rosaos.config import DeviceConfig
    from rosaos.intents.grammar.vocabulary import sources_from_config
    from rosaos.intents.understanding.matching import IntentMatcher
    from rosaos.plugins import load_drivers

    devices = {
        name: DeviceConfig(driver=spec["driver"], description=spec.get("description"))
        for name, spec in world.items()
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


def _judge(world: dict[str, Any]) -> tuple[EngineJudge, Any]:
    """The judge ``rosaos voice`` gets from the kernel of ``world`` (``POST /understand``: whole, and
    no robot set moving, with the world's names), and its engine's own ``is_exact``."""
    from rosaos.plugins import load_drivers

    matcher = _matcher(world)
    drivers = load_drivers()
    halts = {
        name: drivers.drivers[spec["driver"]].spec.halts
        for name, spec in world.items()
        if spec["driver"] in drivers.drivers
    }

    def acts_without_moving(text: str) -> bool:
        result = matcher.match(text)
        return result.is_exact and not result.starts_motion(lambda name: halts.get(name, ()))

    return EngineJudge(acts_without_moving, world_phrases(world)), lambda text: matcher.match(text).is_exact


def false_early_ends(stt: MoonshineSTT | None, work: Path, verbose: bool = False) -> dict[str, Any]:
    """Judge every beginning of every public sentence; ``stt`` None: written beginnings only."""
    engines: dict[int, tuple[EngineJudge, Any, Any]] = {}
    rows = []
    whole_sentences = 0
    sentences = public_sentences()
    for number, (sentence, world) in enumerate(sentences):
        key = id(world)
        if key not in engines:
            engines[key] = (*_judge(world), command_reader(world))
        judge, exact, read = engines[key]
        whole_sentences += asyncio.run(is_whole_command(judge, sentence, WAKE))
        intended = read(sentence)
        words = sentence.split()
        if stt is not None:
            stt.bias_toward(world_phrases(world))
        for cut in range(1, len(words)):
            beginning = " ".join(words[:cut])
            heard = {"written": beginning}
            if stt is not None:
                wav = work / f"beginning-{number}-{cut}.wav"
                if not wav.exists():
                    subprocess.run(["espeak-ng", "-w", str(wav), beginning], check=True)
                audio = read_wav(wav)
                audio = audio[: np.flatnonzero(np.abs(audio) > 1e-4)[-1] + 1]  # espeak's own tail off
                padded = np.concatenate([audio, np.zeros(round(POST_ROLL_SECONDS * SAMPLE_RATE), np.float32)])
                heard["spoken"] = stt.transcribe_sync(padded)
            for how, text in heard.items():
                command = command_of(text, WAKE)
                different = read(command) != intended  # a beginning that means the same is no harm
                alone = bool(command.strip()) and exact(command) and different
                cut = asyncio.run(is_whole_command(judge, text, WAKE)) and different
                rows.append(
                    {
                        "sentence": sentence,
                        "how": how,
                        "beginning": beginning,
                        "heard": text,
                        "false_end_engine_alone": alone,
                        "false_end": cut,
                    }
                )
                if verbose and alone:
                    print(f"  {how}: {text!r} of {sentence!r}{'  [CUT]' if cut else ''}")
    if stt is not None:
        stt.bias_toward([])
    out: dict[str, Any] = {
        "sentences": len(sentences),
        "whole_sentences_judged_whole": round(whole_sentences / max(1, len(sentences)), 3),
    }
    for how in ("written", "spoken"):
        mine = [row for row in rows if row["how"] == how]
        if not mine:
            continue
        out[how] = {
            "beginnings": len(mine),
            "false_early_ends_engine_alone": sum(row["false_end_engine_alone"] for row in mine),
            "false_early_ends": sum(row["false_end"] for row in mine),
            "false_early_end_rate": round(sum(row["false_end"] for row in mine) / max(1, len(mine)), 3),
            "cut": [{"sentence": row["sentence"], "heard": row["heard"]} for row in mine if row["false_end"]],
        }
    return out


def describe(result: dict[str, Any]) -> list[str]:
    """Lines for people."""
    lines = [
        f"end of turn by meaning: {result['whole_sentences_judged_whole']:.0%} of the "
        f"{result['sentences']} public sentences are judged whole (their turn ends after 0.18 s)"
    ]
    for how in ("spoken", "written"):
        if how in result:
            figures = result[how]
            lines.append(
                f"false early ends ({how} beginnings, cut after each word): {figures['false_early_ends']} "
                f"of {figures['beginnings']} ({figures['false_early_end_rate']:.1%}) "
                f"({figures['false_early_ends_engine_alone']} with the engine's is_exact alone)"
            )
            lines += [f"    would cut {row['sentence']!r} at {row['heard']!r}" for row in figures["cut"]]
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--written-only", action="store_true", help="no speech: judge the written words")
    parser.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="rosaos-voice-turns-")))
    options = parser.parse_args()
    options.work.mkdir(parents=True, exist_ok=True)
    stt = None if options.written_only else MoonshineSTT()
    result = false_early_ends(stt, options.work, verbose=True)
    print("\n".join(describe(result)))


if __name__ == "__main__":
    main()
