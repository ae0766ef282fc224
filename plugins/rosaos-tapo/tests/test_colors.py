"""The named-colour table behind set_color_name."""

from __future__ import annotations

import pytest

from rosaos_tapo.colors import (
    NAMED_COLORS,
    Color,
    UnknownColorError,
    White,
    lookup_color,
    normalize_color_name,
)


def test_colour_names_are_normalised() -> None:
    assert normalize_color_name("  Warm-White ") == "warm white"


def test_lookup_finds_a_colour_with_hue_and_saturation() -> None:
    assert lookup_color("Red") == Color(hue=0, saturation=100)


def test_lookup_finds_a_white_as_a_colour_temperature() -> None:
    assert lookup_color("warm_white") == White(kelvin=2700)


def test_every_named_value_is_within_the_bulbs_range() -> None:
    for name, color in NAMED_COLORS.items():
        if isinstance(color, White):
            assert 2500 <= color.kelvin <= 6500, name
        else:
            assert 0 <= color.hue <= 360, name
            assert 0 < color.saturation <= 100, name


def test_unknown_name_suggests_close_matches() -> None:
    with pytest.raises(UnknownColorError, match=r"did you mean 'purple'"):
        lookup_color("purpel")


def test_unknown_name_without_close_match_has_no_suggestion() -> None:
    with pytest.raises(UnknownColorError) as raised:
        lookup_color("zzz")
    assert "did you mean" not in str(raised.value)
    assert "known colours: red" in str(raised.value)
