"""Fixtures for the local-intent engine tests."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

# Test modules import intents_support from this folder (pytest's importlib mode does not put it
# on sys.path).
HERE = str(Path(__file__).parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)

from intents_support import home_world  # noqa: E402

from rosaos.intents.understanding.matching import IntentMatcher  # noqa: E402


@pytest.fixture(scope="session")
def matcher() -> IntentMatcher:
    """The English matcher of the test home world (built once: building compiles grammars)."""
    return IntentMatcher(home_world(), "en")


@pytest.fixture(scope="session")
def matcher_fr() -> IntentMatcher:
    """The same world, in French."""
    return IntentMatcher(home_world(), "fr")
