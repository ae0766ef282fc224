"""Emotions and dances: the built-in keyframes, or Pollen's recorded moves when they are cached.

Pollen Robotics publishes recorded emotions and dances as Hugging Face datasets, which the SDK
downloads on first use. rosaOS never downloads at run time, so :class:`MoveLibrary` uses a
dataset only when it is already in the local Hugging Face cache (``local_files_only``), and
otherwise its own keyframes from ``data/moves.yaml``. :meth:`MoveLibrary.listing` says which.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import yaml
from reachy_mini.motion.move import Move
from reachy_mini.motion.recorded_move import SOUND_EXTENSIONS, RecordedMove
from reachy_mini.utils.interpolation import linear_pose_interpolation

from rosaos_reachy.robot import HeadPose, Posture, antennas_from_sdk, antennas_to_sdk

log = logging.getLogger(__name__)

MovesKind = Literal["emotions", "dances"]
KINDS: tuple[MovesKind, ...] = ("emotions", "dances")
MOVES_FILE = Path(__file__).parent / "data" / "moves.yaml"
LEAD_IN_S = 0.5
"""Seconds to ease from the current pose to a recorded move's first frame."""
_HEAD_KEYS = ("x", "y", "z", "roll", "pitch", "yaw")


@dataclass(frozen=True)
class Keyframe:
    t: float
    head: dict[str, float]
    antennas: tuple[float, float] | None
    body: float | None


@dataclass(frozen=True)
class KeyframeSpec:
    """One built-in move: its keyframes, relative to the pose it starts from."""

    name: str
    description: str
    keyframes: tuple[Keyframe, ...]
    return_s: float = 0.5

    def move(self, start: Posture) -> KeyframeMove:
        """The SDK :class:`Move` that plays this from ``start`` and eases back to it."""
        frames: list[tuple[float, Posture]] = [(0.0, start)]
        head = dict.fromkeys(_HEAD_KEYS, 0.0)
        antennas, body = start.antennas, 0.0
        for key in self.keyframes:
            head.update(key.head)
            antennas = key.antennas if key.antennas is not None else antennas
            body = key.body if key.body is not None else body
            pose = HeadPose(**{k: getattr(start.head, k) + head[k] for k in _HEAD_KEYS})
            frames.append((key.t, Posture(pose, antennas, start.body_yaw + body)))
        frames.append((self.keyframes[-1].t + self.return_s, start))
        return KeyframeMove(frames)


class KeyframeMove(Move):
    """Eased interpolation through postures, as an SDK :class:`Move`."""

    def __init__(self, frames: list[tuple[float, Posture]]) -> None:
        self.frames = frames

    @property
    def duration(self) -> float:
        return self.frames[-1][0]

    def posture_at(self, t: float) -> Posture:
        """The posture at ``t`` seconds: cosine-eased between the surrounding keyframes."""
        for (t0, a), (t1, b) in zip(self.frames, self.frames[1:], strict=False):
            if t <= t1:
                alpha = 0.5 - 0.5 * math.cos(math.pi * min(1.0, max(0.0, (t - t0) / max(t1 - t0, 1e-6))))
                return _mix(a, b, alpha)
        return self.frames[-1][1]

    def evaluate(self, t: float) -> tuple[np.ndarray[Any, Any], np.ndarray[Any, Any], float]:
        posture = self.posture_at(t)
        return (
            posture.head.matrix(),
            np.array(antennas_to_sdk(*posture.antennas)),
            math.radians(posture.body_yaw),
        )


def _mix(a: Posture, b: Posture, alpha: float) -> Posture:
    def mix(u: float, v: float) -> float:
        return u + (v - u) * alpha

    head = HeadPose(**{k: mix(getattr(a.head, k), getattr(b.head, k)) for k in _HEAD_KEYS})
    antennas = (mix(a.antennas[0], b.antennas[0]), mix(a.antennas[1], b.antennas[1]))
    return Posture(head, antennas, mix(a.body_yaw, b.body_yaw))


class LeadIn(Move):
    """A recorded move, preceded by an eased approach from the current pose to its first frame."""

    def __init__(self, move: RecordedMove, start: Posture) -> None:
        self.move = move
        self.start = start

    @property
    def duration(self) -> float:
        return LEAD_IN_S + float(self.move.duration)

    def evaluate(self, t: float) -> tuple[Any, Any, float]:
        if t >= LEAD_IN_S:
            return self.move.evaluate(min(t - LEAD_IN_S, float(self.move.duration) - 1e-3))
        head, antennas, body = self.move.evaluate(0.0)
        alpha = 0.5 - 0.5 * math.cos(math.pi * t / LEAD_IN_S)
        start_antennas = np.array(antennas_to_sdk(*self.start.antennas))
        start_body = math.radians(self.start.body_yaw)
        return (
            linear_pose_interpolation(self.start.head.matrix(), np.asarray(head), alpha),
            start_antennas + (np.asarray(antennas) - start_antennas) * alpha,
            start_body + (float(body) - start_body) * alpha,
        )

    def end(self) -> Posture:
        """Where the recorded move leaves the robot."""
        head, antennas, body = self.move.evaluate(float(self.move.duration) - 1e-3)
        return Posture(HeadPose.from_matrix(head), antennas_from_sdk(antennas), math.degrees(float(body)))


@dataclass
class Dataset:
    """A recorded-move dataset found in the local Hugging Face cache."""

    name: str
    path: Path
    moves: dict[str, Path] = field(default_factory=dict)

    def recorded(self, move: str) -> tuple[RecordedMove, Path | None]:
        json_path = self.moves[move]
        sound = next((p for ext in SOUND_EXTENSIONS if (p := json_path.with_suffix(ext)).exists()), None)
        return RecordedMove(json.loads(json_path.read_text()), sound), sound


def cached_dataset(name: str, cache_dir: Path | None = None) -> Dataset | None:
    """The dataset ``name`` if it is in the local Hugging Face cache; never downloads."""
    from huggingface_hub import snapshot_download  # the SDK's dependency; imported when needed

    try:
        path = Path(snapshot_download(name, repo_type="dataset", local_files_only=True, cache_dir=cache_dir))
    except Exception:  # LocalEntryNotFoundError, or an offline/invalid cache: not available
        return None
    files = sorted([*path.glob("*.json"), *path.glob("data/*.json")])
    moves = {p.stem: p for p in files if _is_recorded_move(p)}
    return Dataset(name, path, moves) if moves else None


def _is_recorded_move(path: Path) -> bool:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and "set_target_data" in data and "time" in data


class UnknownMove(LookupError):
    """A move name that is in no source; the message lists what there is."""


@dataclass(frozen=True)
class Choice:
    """A move resolved to what plays it."""

    name: str
    source: str
    spec: KeyframeSpec | None = None
    recorded: RecordedMove | None = None
    sound: Path | None = None

    def move(self, start: Posture) -> tuple[Move, Posture]:
        """The SDK :class:`Move` to stream from ``start``, and the posture it ends in."""
        if self.spec is not None:
            return self.spec.move(start), start
        assert self.recorded is not None
        lead_in = LeadIn(self.recorded, start)
        return lead_in, lead_in.end()


class MoveLibrary:
    """Built-in emotions and dances, plus the recorded datasets that are cached locally."""

    def __init__(
        self,
        emotions_dataset: str,
        dances_dataset: str,
        cache_dir: Path | None = None,
        path: Path = MOVES_FILE,
    ) -> None:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
        self.builtin: dict[MovesKind, dict[str, KeyframeSpec]] = {
            "emotions": _specs(raw["emotions"]),
            "dances": _specs(raw["dances"]),
        }
        self.aliases: dict[str, str] = {str(k): str(v) for k, v in (raw.get("aliases") or {}).items()}
        self.dataset_names: dict[MovesKind, str] = {"emotions": emotions_dataset, "dances": dances_dataset}
        self.cache_dir = cache_dir
        self.datasets: dict[MovesKind, Dataset | None] = {"emotions": None, "dances": None}

    def refresh(self) -> None:
        """Look for the datasets in the local cache (blocking: a few file reads)."""
        for kind, name in self.dataset_names.items():
            self.datasets[kind] = cached_dataset(name, self.cache_dir)

    def source(self, kind: MovesKind) -> str:
        """``dataset <name>`` when the recorded moves are cached, else ``built-in``."""
        dataset = self.datasets[kind]
        return f"dataset {dataset.name}" if dataset is not None else "built-in"

    def resolve(self, kind: MovesKind, name: str) -> Choice:
        """The move called ``name``: from the cached dataset first, then the built-in set."""
        key = name.strip().lower().replace(" ", "_")
        dataset = self.datasets[kind]
        if dataset is not None:
            match = next((m for m in dataset.moves if m.lower() == key), None)
            if match is not None:
                recorded, sound = dataset.recorded(match)
                return Choice(match, f"dataset {dataset.name}", recorded=recorded, sound=sound)
        key = self.aliases.get(key, key)
        spec = self.builtin[kind].get(key)
        if spec is None:
            raise UnknownMove(f"no {kind[:-1]} called {name!r}; {kind}: {', '.join(self.names(kind))}")
        return Choice(spec.name, "built-in", spec=spec)

    def names(self, kind: MovesKind) -> list[str]:
        dataset = self.datasets[kind]
        recorded = list(dataset.moves) if dataset is not None else []
        return recorded + [n for n in self.builtin[kind] if n not in recorded]

    def listing(self) -> dict[str, Any]:
        """What ``list_emotions`` returns: names, descriptions and the source in use."""
        result: dict[str, Any] = {}
        for kind in KINDS:
            dataset = self.datasets[kind]
            result[kind] = {
                "source": self.source(kind),
                "recorded": list(dataset.moves) if dataset is not None else [],
                "built_in": {name: spec.description for name, spec in self.builtin[kind].items()},
            }
        result["aliases"] = dict(self.aliases)
        return result


def _specs(raw: dict[str, Any]) -> dict[str, KeyframeSpec]:
    specs = {}
    for name, entry in raw.items():
        keyframes = tuple(
            Keyframe(
                t=float(k["t"]),
                head={h: float(k[h]) for h in _HEAD_KEYS if h in k},
                antennas=(float(k["antennas"][0]), float(k["antennas"][1])) if "antennas" in k else None,
                body=float(k["body"]) if "body" in k else None,
            )
            for k in entry["keyframes"]
        )
        specs[str(name)] = KeyframeSpec(
            str(name), str(entry["description"]), keyframes, float(entry.get("return", 0.5))
        )
    return specs
