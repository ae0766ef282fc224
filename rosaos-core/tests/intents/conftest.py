"""Fixtures for the local-intent engine tests."""

from __future__ import annotations

import pytest

from rosaos.intents.understanding.matching import IntentMatcher

from .intents_support import home_world


@pytest.fixture(scope="session")
def matcher() -> IntentMatcher:
    """The English matcher of the test home world (built once: building compiles grammars)."""
    return IntentMatcher(home_world(), "en")


@pytest.fixture(scope="session")
def matcher_fr() -> IntentMatcher:
    """The same world, in French."""
    return IntentMatcher(home_world(), "fr")
