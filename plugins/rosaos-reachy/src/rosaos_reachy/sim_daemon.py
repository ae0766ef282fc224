"""Run ``reachy-mini-daemon --sim`` with its MuJoCo scene loaded pre-compiled: 160 MiB lighter.

Why: compiling the Reachy Mini's scene from XML (its meshes: 174k vertices) leaves about
160 MiB of the C++ heap allocated for good in MuJoCo 3.3: ``mallinfo2`` counts it in use after
the model is freed, and neither ``malloc_trim``, the allocator's environment variables nor
MuJoCo's asset cache size return it. Loading the same model from its binary form (``.mjb``,
MuJoCo's own format, written by ``mj_saveModel``) does not compile at all, so the daemon idles at
about 215 MiB instead of 375, and boots 0.5 s sooner.

The simulation is the same one: an ``.mjb`` holds the compiled model, every array bit for bit
(``tests/test_sim_daemon.py`` compares all of them and a stretch of physics steps). The scene is
compiled once per MuJoCo version and scene files, in a short-lived child process whose heap is
returned when it exits, and kept in ``--model-cache``. Anything that goes wrong on the way
(no cache directory, a failed compile) is logged and the daemon compiles the XML itself, as it
always did: slower and heavier, never broken.

    python -m rosaos_reachy.sim_daemon --model-cache DIR -- <reachy-mini-daemon arguments>
    python -m rosaos_reachy.sim_daemon --compile SCENE.xml OUT.mjb
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
from collections.abc import Callable
from importlib.metadata import version
from importlib.resources import files
from pathlib import Path
from typing import Any

import platformdirs

SCENE = "empty"
"""The scene the daemon loads (``--scene``); the launcher passes it explicitly so both agree."""


def default_model_cache() -> Path:
    """Where compiled scenes are kept: the user's cache directory, shared by every data directory
    (an ``.mjb`` is 80 MB, and compiling it costs a second of CPU)."""
    return Path(platformdirs.user_cache_dir("rosaos", appauthor=False)) / "reachy-scenes"


def scene_xml(scene: str = SCENE) -> Path:
    """The daemon's MJCF file for ``scene``, where the SDK's MuJoCo backend reads it."""
    mjcf = files("reachy_mini").joinpath("descriptions/reachy_mini/mjcf")
    return Path(str(mjcf)).resolve() / "scenes" / f"{scene}.xml"


def cache_key(xml: Path) -> str:
    """A digest of the MuJoCo version and every file the scene can include (XML, meshes).

    Any change to either compiles the scene anew, so a stale model is never loaded.
    """
    digest = hashlib.sha256(f"mujoco {version('mujoco')}\n".encode())
    root = xml.parent.parent  # mjcf/: the scene, the robot's XML and its assets
    for path in sorted(p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
        digest.update(str(path.relative_to(root)).encode() + b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()[:20]


def compile_scene(xml: Path, out: Path) -> None:
    """Compile ``xml`` and write the model to ``out`` (atomically: a reader sees all or nothing)."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(xml))
    partial = out.with_name(f"{out.name}.{os.getpid()}.part")
    mujoco.mj_saveModel(model, str(partial), None)
    os.replace(partial, out)


def compiled_scene(xml: Path, cache: Path) -> Path:
    """The ``.mjb`` of ``xml`` in ``cache``, compiled by a child process if it is not there yet.

    The child is what keeps the compiler's heap out of the daemon: it exits once the file is
    written. Raises ``RuntimeError`` (with the child's output) when the compile fails.
    """
    out = cache / f"{xml.stem}-{cache_key(xml)}.mjb"
    if out.is_file():
        return out
    cache.mkdir(parents=True, exist_ok=True)
    done = subprocess.run(
        [sys.executable, "-m", "rosaos_reachy.sim_daemon", "--compile", str(xml), str(out)],
        stdin=subprocess.DEVNULL, capture_output=True, text=True, check=False,
    )  # fmt: skip
    if done.returncode != 0 or not out.is_file():
        raise RuntimeError(f"compiling {xml} failed ({done.returncode}): {done.stderr.strip()[-500:]}")
    for stale in cache.glob(f"{xml.stem}-*.mjb"):  # other MuJoCo versions or scene files
        if stale != out:
            stale.unlink(missing_ok=True)
    return out


def serve_compiled(xml: Path, compiled: Path) -> None:
    """Make ``MjModel.from_xml_path(xml)`` load ``compiled`` instead; any other path is untouched.

    This is the one call through which the SDK's MuJoCo backend loads its scene.
    """
    import mujoco

    original: Callable[..., Any] = mujoco.MjModel.from_xml_path

    def from_xml_path(filename: str, assets: dict[str, bytes] | None = None) -> Any:
        if assets is None and Path(filename).resolve() == xml:
            try:
                model = mujoco.MjModel.from_binary_path(str(compiled))
            except Exception as error:  # e.g. removed since by another version's compile
                print(f"rosaos: compiling the scene ({compiled}: {error})", file=sys.stderr, flush=True)
                return original(filename)
            print(f"rosaos: loaded the compiled scene {compiled}", file=sys.stderr, flush=True)
            return model
        return original(filename) if assets is None else original(filename, assets)

    mujoco.MjModel.from_xml_path = staticmethod(from_xml_path)


def run_daemon(model_cache: Path, daemon_args: list[str]) -> int:
    """Run the SDK's daemon in this process with its scene served pre-compiled (when possible)."""
    xml = scene_xml()
    try:
        serve_compiled(xml, compiled_scene(xml, model_cache))
    except (OSError, RuntimeError) as error:
        print(f"rosaos: the daemon compiles its scene itself ({error})", file=sys.stderr, flush=True)
    from reachy_mini.daemon.app.main import main

    sys.argv = ["reachy-mini-daemon", *daemon_args]
    result = main()
    return result if isinstance(result, int) else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--model-cache", type=Path, help="directory of compiled scenes")
    parser.add_argument("--compile", nargs=2, type=Path, metavar=("XML", "OUT"), help=argparse.SUPPRESS)
    parser.add_argument("daemon_args", nargs="*", help="arguments for reachy-mini-daemon, after --")
    args = parser.parse_args()
    if args.compile:
        compile_scene(*args.compile)
        return 0
    if args.model_cache is None:
        parser.error("--model-cache DIR is required to run the daemon")
    return run_daemon(args.model_cache, args.daemon_args)


if __name__ == "__main__":
    sys.exit(main())
