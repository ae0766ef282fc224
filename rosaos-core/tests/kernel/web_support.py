"""Shared by the web page's browser tests: Chromium on the served app, and a desk of devices whose
cards are the ones the built-in drivers really declare. Screenshots go to ``artifacts/web/``."""

from __future__ import annotations

import shutil
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
from playwright.async_api import Page, async_playwright

from rosaos.plugins import load_drivers

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
ARTIFACTS = Path(__file__).resolve().parents[3] / "artifacts" / "web"


def card_of(driver: str) -> dict[str, Any]:
    card = load_drivers().drivers[driver].spec.card
    assert card is not None, driver
    return card.view()


def device(name: str, driver: str, state: dict[str, Any]) -> dict[str, Any]:
    return {
        "name": name,
        "driver": driver,
        "concurrency": "exclusive",
        "backend": "sim",
        "status": "healthy",
        "state": state,
        "description": f"a simulated {driver}",
        "card": card_of(driver),
    }


def desk() -> list[dict[str, Any]]:
    return [
        device(
            "reachy",
            "reachy",
            {
                "head": {"x": 0, "y": 0, "z": 0, "roll": 5.0, "pitch": -10.0, "yaw": 30.0},
                "antennas": [40.0, -20.0],
                "body_yaw": 0.0,
                "awake": True,
                "last_spoken": "Hello there",
                "speaking": False,
                "moving": None,
                "mode": "sim: mockup",
            },
        ),
        device("turtlebot", "ros", {"x": 0.0, "y": 0.0, "yaw": 0.0, "docked": True, "battery": 0.87}),
        device(
            "spotify",
            "spotify",
            {
                "is_playing": True,
                "volume": 40,
                "track": "So What",
                "artist": "Miles Davis",
                "shuffle": False,
                "repeat": "off",
            },
        ),
        device(
            "kitchen_light",
            "tapo",
            {"on": True, "brightness": 100, "hue": 0, "saturation": 100, "color_temp": 0},
        ),
        device(
            "living_room_lamp",
            "tapo",
            {"on": True, "brightness": 60, "hue": 0, "saturation": 0, "color_temp": 2700},
        ),
    ]


@pytest.fixture
async def page(served: str) -> AsyncIterator[Page]:
    if CHROMIUM is None:
        pytest.skip("Chromium is not installed (apt install chromium)")
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        context = await browser.new_context(base_url=served, viewport={"width": 1280, "height": 900})
        opened = await context.new_page()
        errors: list[str] = []
        opened.on("pageerror", lambda error: errors.append(str(error)))
        opened.on("console", lambda message: errors.append(message.text) if message.type == "error" else None)
        opened.errors = errors  # type: ignore[attr-defined]
        yield opened
        await browser.close()


def card(name: str) -> str:
    return f'.device-card[data-device="{name}"]'
