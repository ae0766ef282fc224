"""How well the offline voice path hears the public task sentences: word and command error rates.

Every one-sentence public task (``shared/bench/tasks``) is spoken by espeak-ng in three conditions:
its default speed (175 words a minute), fast (230), and the default speed with white noise mixed
in at 10 dB SNR (seeded, so every run hears the same noise). Moonshine transcribes each, biased
toward the words of that task file's world (``--no-bias`` to compare without).

- **word error rate**: word edits per reference word, over all sentences of a condition;
- **command error rate**: the share of sentences whose command, as the offline engine reads what
  was heard, is not the one it reads from what was said: other processes or plans, or a plan where
  the sentence had none (or none where it had one). A sentence the engine does not act on even
  as written (an ambiguous one) counts as right when what was heard is not acted on either.

Run alone: ``.venv/bin/python benchmarks/voice_accuracy.py [--no-bias]``; ``voice.py`` runs it too.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from rosaos.frontends.voice.sources import read_wav
from rosaos.frontends.voice.stt import MoonshineSTT, word_error_rate
from rosaos.frontends.voice.word_bias import world_phrases

PUBLIC_TASKS = next(
    (
        folder / "shared" / "bench" / "tasks"
        for folder in Path(__file__).resolve().parents
        if (folder / "shared" / "bench" / "tasks").is_dir()
    ),
    Path(__file__).resolve().parents[2] / "shared" / "bench" / "tasks",
)
"""The public task files, in a ``shared/bench/tasks`` next to the repository or above it."""
CONDITIONS: dict[str, tuple[list[str], float | None]] = {
    "espeak 175 wpm": ([], None),
    "espeak 230 wpm": (["-s", "230"], None),
    "espeak 175 wpm, noise 10 dB SNR": ([], 10.0),
}
"""espeak-ng arguments and the signal-to-noise ratio of mixed-in white noise (None: clean)."""


def public_sentences() -> list[tuple[str, dict[str, Any]]]:
    """(sentence, world of its task file) for every one-sentence public task."""
    found = []
    for path in sorted(PUBLIC_TASKS.glob("*.yaml")):
        data = yaml.safe_load(path.read_text())
        found += [(task["say"], data["world"]) for task in data["tasks"] if isinstance(task.get("say"), str)]
    return found


def with_noise(samples: np.ndarray, snr_db: float, seed: int) -> np.ndarray:
    """``samples`` plus white noise ``snr_db`` below the speech's power (silence not counted)."""
    speech = samples[np.abs(samples) > 1e-4]
    power = float(np.mean(np.square(speech))) if speech.size else 1e-6
    noise = np.random.default_rng(seed).normal(0.0, np.sqrt(power / 10 ** (snr_db / 10)), samples.size)
    return np.clip(samples + noise, -1, 1).astype(np.float32)


def transcripts(
    stt: MoonshineSTT,
    work: Path,
    bias: bool = True,
    conditions: list[str] | None = None,
    verbose: bool = False,
) -> dict[str, list[dict[str, Any]]]:
    """What the engine heard of every sentence, per condition (all of them unless ``conditions``)."""
    sentences = public_sentences()
    heard: dict[str, list[dict[str, Any]]] = {}
    for condition, (args, snr) in CONDITIONS.items():
        if conditions is not None and condition not in conditions:
            continue
        rows = []
        for number, (sentence, world) in enumerate(sentences):
            wav = work / f"sentence-{number}{'-'.join(args)}.wav"
            if not wav.exists():
                subprocess.run(["espeak-ng", *args, "-w", str(wav), sentence], check=True)
            audio = read_wav(wav)
            if snr is not None:
                audio = with_noise(audio, snr, seed=number)
            stt.bias_toward(world_phrases(world) if bias else [])
            rows.append({"said": sentence, "heard": stt.transcribe_sync(audio), "world": world})
            if verbose:
                print(f"  {condition}: {sentence!r} → {rows[-1]['heard']!r}", flush=True)
        heard[condition] = rows
    stt.bias_toward([])
    return heard


def command_reader(world: dict[str, Any]) -> Callable[[str], Any]:
    """The offline engine of ``world``: a sentence → what would run (None when nothing would)."""
    from rosaos.config import DeviceConfig
    from rosaos.intents.grammar.vocabulary import sources_from_config
    from rosaos.intents.understanding.matching import IntentMatcher
    from rosaos.plugins import load_drivers

    devices = {
        name: DeviceConfig(driver=spec["driver"], description=spec.get("description"))
        for name, spec in world.items()
    }
    matcher = IntentMatcher(sources_from_config(devices, load_drivers()), "en")

    def read(sentence: str) -> Any:
        result = matcher.match(sentence)
        if not result.is_exact:
            return None
        plans = (json.dumps(p.plan.model_dump(), sort_keys=True).lower() for p in result.processes)
        return sorted(plans)  # case aside: "Here Comes the Sun" and "here comes the sun" play the same

    return read


def scores(heard: dict[str, list[dict[str, Any]]]) -> dict[str, Any]:
    """Word and command error rates per condition, and what was misheard."""
    readers: dict[int, Callable[[str], Any]] = {}
    out: dict[str, Any] = {}
    for condition, rows in heard.items():
        edits = words = 0.0
        wrong_commands = 0
        misheard = []
        for row in rows:
            key = id(row["world"])  # one world object per task file (its keys are not all strings)
            if key not in readers:
                readers[key] = command_reader(row["world"])
            read = readers[key]
            count = len(row["said"].split())
            errors = word_error_rate(row["said"], row["heard"]) * count
            edits, words = edits + errors, words + count
            wrong = read(row["said"]) != read(row["heard"])
            wrong_commands += wrong
            if errors or wrong:
                misheard.append({"said": row["said"], "heard": row["heard"], "command_wrong": wrong})
        out[condition] = {
            "sentences": len(rows),
            "word_error_rate": round(edits / max(1.0, words), 3),
            "command_error_rate": round(wrong_commands / max(1, len(rows)), 3),
            "misheard": misheard,
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-bias", action="store_true", help="transcribe without the vocabulary bias")
    parser.add_argument(
        "--condition", action="append", choices=list(CONDITIONS), help="only these (repeatable)"
    )
    parser.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="rosaos-voice-accuracy-")))
    options = parser.parse_args()
    options.work.mkdir(parents=True, exist_ok=True)
    heard = transcripts(MoonshineSTT(), options.work, not options.no_bias, options.condition, verbose=True)
    result = scores(heard)
    for condition, figures in result.items():
        print(
            f"{condition}: WER {figures['word_error_rate']:.3f}, "
            f"command error rate {figures['command_error_rate']:.3f} ({figures['sentences']} sentences)"
        )
        for row in figures["misheard"]:
            print(
                f"    said {row['said']!r:50} heard {row['heard']!r}{'  [command wrong]' if row['command_wrong'] else ''}"
            )


if __name__ == "__main__":
    main()
