"""Fixtures for the offline model adapters' tests: they share the engine tests' worlds and servers."""

from __future__ import annotations

import sys
from pathlib import Path

# The adapters' tests import intents_support from tests/intents (pytest's importlib mode does
# not put it on sys.path).
INTENTS_TESTS = str(Path(__file__).parent.parent / "intents")
if INTENTS_TESTS not in sys.path:
    sys.path.insert(0, INTENTS_TESTS)
