"""Native libraries, tried in a child process before rosaOS trusts them with its own.

A wheel built for newer CPUs than it claims (AVX-512 on a CPU without it) does not raise: the
process dies with SIGILL, and with it the kernel or the voice front end. So a default path that
loads such a library first runs a short Python snippet that loads and exercises it in a child.
If the child dies by a signal, the caller gets a :class:`NativeCheck` that names the library, the
signal and what the CPU lacks, and can refuse with a message instead of dying.
"""

from __future__ import annotations

import platform
import re
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

PROBE_TIMEOUT = 120.0
"""Seconds a probe may take (loading a model under emulation or on a Raspberry Pi is slow)."""
WIDE_VECTOR_FLAGS = ("avx512f", "avx512bw", "avx512vl", "avx512dq", "avx512cd", "avx2", "fma", "f16c")


@dataclass(frozen=True)
class NativeCheck:
    """How loading one native library in a child process went."""

    library: str
    ok: bool
    detail: str
    """Empty when ok; else what happened (the signal, or the child's last lines of stderr)."""

    def explain(self) -> str:
        """One paragraph for a person: what failed, on which CPU, and what to do instead."""
        if self.ok:
            return f"{self.library} loads on this CPU"
        return f"{self.library} cannot run on this machine ({self.detail}; CPU: {cpu_summary()})"


def cpu_flags() -> set[str]:
    """The CPU feature flags Linux reports (empty elsewhere)."""
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return set()
    match = re.search(r"^(flags|Features)\s*:\s*(.*)$", text, re.MULTILINE)
    return set(match.group(2).split()) if match else set()


def cpu_summary() -> str:
    """The machine and which wide-vector extensions it has, e.g. ``x86_64, avx2 fma, no avx512f``."""
    flags = cpu_flags()
    have = [flag for flag in WIDE_VECTOR_FLAGS if flag in flags]
    lacks = [flag for flag in ("avx512f", "avx2") if flag not in flags]
    parts = [platform.machine() or "unknown"]
    if have:
        parts.append(" ".join(have))
    if lacks and platform.machine() in ("x86_64", "AMD64"):
        parts.append("no " + " ".join(lacks))
    return ", ".join(parts)


def probe(library: str, code: str, timeout: float = PROBE_TIMEOUT) -> NativeCheck:
    """Run ``code`` in a fresh interpreter (``python -P -c``); a signal or a non-zero exit fails."""
    try:
        done = subprocess.run(
            [sys.executable, "-P", "-c", code],
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return NativeCheck(library, False, f"loading it took over {timeout:.0f} s")
    if done.returncode < 0:
        try:
            name = signal.Signals(-done.returncode).name
        except ValueError:
            name = f"signal {-done.returncode}"
        why = " (an instruction this CPU does not have)" if name == "SIGILL" else ""
        return NativeCheck(library, False, f"a test load died with {name}{why}")
    if done.returncode != 0:
        tail = " ".join(done.stderr.strip().splitlines()[-2:])[-400:]
        return NativeCheck(library, False, f"a test load failed: {tail or f'exit {done.returncode}'}")
    return NativeCheck(library, True, "")
