"""Card declarations: what a driver may declare, what the page receives, and the kit's key check."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from rosaos.cards import Card, CardWidget, card_keys_missing, flag, gauge, image, pose, swatch, text
from rosaos.drivers import DriverSpec
from rosaos.plugins import load_drivers


def test_compound_widgets_reach_the_page_with_every_role_mapped() -> None:
    view = Card.of(swatch(keys={"brightness": "level"}), pose()).view()
    lamp, robot = view["widgets"]
    assert lamp["kind"] == "swatch"
    assert lamp["keys"] == {
        "on": "on",
        "brightness": "level",
        "hue": "hue",
        "saturation": "saturation",
        "color_temp": "color_temp",
    }
    assert robot["keys"]["people"] == "people_seen"  # the agreed key for detections on the map


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: CardWidget(kind="gauge"), "needs key"),
        (lambda: gauge("volume", min=10, max=10), "must be above min"),
        (lambda: swatch(keys={"colour": "c"}), "has no role colour"),
        (lambda: CardWidget(kind="sparkline", key="x"), "kind"),
        (lambda: Card(widgets=[]), "at least 1"),
    ],
)
def test_a_wrong_declaration_is_refused_with_the_reason(build: object, message: str) -> None:
    with pytest.raises(ValidationError, match=message):
        build()  # type: ignore[operator]


def test_missing_keys_are_named_and_optional_roles_may_be_absent() -> None:
    card = Card.of(pose(), flag("docked"), text("mode"), image())
    assert card_keys_missing(card, {"x": 0.0, "y": 1.0, "docked": True, "mode": None}) == []
    assert card_keys_missing(card, {"x": 0.0, "docked": True}) == ["y", "mode"]


def test_every_built_in_driver_declares_a_card() -> None:
    registry = load_drivers()
    kinds = {
        name: [w.kind for w in info.spec.card.widgets]
        for name, info in registry.drivers.items()
        if info.spec.card is not None
    }
    assert kinds["tapo"] == ["swatch"]
    assert "head" in kinds["reachy"] and "image" in kinds["reachy"]
    assert {"text", "gauge", "flag"} <= set(kinds["spotify"])
    assert kinds["ros"][0] == "pose" and "image" in kinds["ros"]


def test_a_driver_spec_without_a_card_is_still_valid() -> None:
    spec = load_drivers().drivers["tapo"].spec
    bare = DriverSpec(**{**spec.model_dump(), "card": None})
    assert bare.card is None
