"""The web page draws what drivers declare: each card kind, camera frames, a template driver's card.

The devices carry the card views the built-in drivers really declare (from their plugins), with
canned state; tests/test_web_end_to_end.py does the same with the real simulators. Screenshots go
to ``artifacts/web/`` at the repository root (gitignored).
"""

from __future__ import annotations

import asyncio
import importlib
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

from playwright.async_api import Page

from rosaos.drivers import DeviceContext
from rosaos.receipts import Receipt

from .kernel_support import TestRuntime
from .web_support import ARTIFACTS, card, desk


async def test_each_card_kind_draws_its_declaration(page: Page, runtime: TestRuntime) -> None:
    runtime.device_list = desk()
    await page.goto(f"/#login={runtime.login_codes.mint()}")
    # A lamp: a swatch of its real colour, named in words, also for screen readers.
    red = f"{card('kitchen_light')} [data-widget-kind=swatch]"
    await page.wait_for_selector(f"{red} .swatch-name:text-is('red, 100 %')")
    assert await page.get_attribute(f"{red} .swatch", "aria-label") == "Colour: red, 100 %"
    assert (
        await page.eval_on_selector(f"{red} .swatch", "e => getComputedStyle(e).backgroundColor")
        == "rgb(255, 0, 0)"
    )
    assert await page.inner_text(f"{card('living_room_lamp')} .swatch-name") == "warm white, 60 %"
    # The speaker: track, artist, play state and a volume bar.
    spotify = card("spotify")
    assert await page.inner_text(f"{spotify} [data-widget-key=track] .widget-value") == "So What"
    assert await page.inner_text(f"{spotify} [data-widget-key=artist] .widget-value") == "Miles Davis"
    assert await page.inner_text(f"{spotify} [data-widget-key=is_playing] .widget-value") == "playing"
    assert await page.get_attribute(f"{spotify} [data-widget-key=volume] meter", "value") == "40"
    # Reachy: a drawing of its head and antennas, in words too, and what it last said.
    reachy = f"{card('reachy')} [data-widget-kind=head]"
    words = await page.get_attribute(f"{reachy} svg", "aria-label")
    assert words == "Head yaw 30°, pitch -10°, roll 5°; antennas 40° and -20°"
    assert "rotate(5)" in (await page.get_attribute(f"{reachy} .head", "transform") or "")
    assert await page.inner_text(f"{reachy} .head-said") == "Last said: “Hello there”"
    # The robot: its pose, dock and battery (a 0-1 reading shown in percent).
    robot = card("turtlebot")
    assert "x 0.00 m, y 0.00 m, heading 0° · on its dock" in await page.inner_text(
        f"{robot} [data-widget-kind=pose]"
    )
    assert await page.inner_text(f"{robot} [data-widget-key=battery] .widget-value") == "87 %"
    # Raw state stays one click (or Enter) away.
    raw = f"{spotify} details.raw"
    assert await page.is_hidden(f"{raw} [data-key=volume]")
    await page.focus(f"{raw} summary")
    await page.keyboard.press("Enter")
    await page.wait_for_selector(f"{raw} [data-key=volume]:text-is('40')")
    # Live: a state change redraws the widget.
    runtime.device_list[4]["state"].update(on=False)
    await page.wait_for_selector(
        f"{card('living_room_lamp')} .swatch-name:text-is('off (warm white when on)')"
    )
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    await page.screenshot(path=str(ARTIFACTS / "cards-desktop.png"), full_page=True)
    assert page.errors == []  # type: ignore[attr-defined]


def generated_driver(dest: Path) -> Any:
    """The plugin module of a driver ``rosaos new-driver`` writes (imported from its source tree)."""
    command = [sys.executable, "-m", "rosaos.cli", "new-driver", "--name", "zeta_fan", "--defaults"]
    subprocess.run([*command, "--dest", str(dest)], check=True, capture_output=True, timeout=120)
    sys.path.insert(0, str(dest / "rosaos-zeta_fan" / "src"))
    try:
        return importlib.import_module("rosaos_zeta_fan.plugin")
    finally:
        sys.path.pop(0)


async def test_a_driver_from_the_template_gets_a_proper_card(
    page: Page, runtime: TestRuntime, tmp_path: Path
) -> None:
    plugin = await asyncio.to_thread(generated_driver, tmp_path)
    spec = plugin.SPEC
    backend = spec.backends["sim"](
        DeviceContext("zeta_fan", "", spec.settings(), "sim", {"on": True, "level": 70})
    )
    state = (await backend.state()).model_dump()
    runtime.device_list = [
        {
            "name": "zeta_fan",
            "driver": "zeta_fan",
            "concurrency": spec.concurrency,
            "backend": "sim",
            "status": "healthy",
            "state": state,
            "description": spec.title,
            "card": spec.card.view(),
        }
    ]
    await page.goto(f"/#login={runtime.login_codes.mint()}")
    fan = card("zeta_fan")
    await page.wait_for_selector(f"{fan} [data-widget-key=on] .widget-value:text-is('on')")
    assert await page.inner_text(f"{fan} [data-widget-key=level] .widget-value") == "70 %"
    assert await page.get_attribute(f"{fan} [data-widget-key=level] meter", "value") == "70"
    assert await page.is_hidden(f"{fan} details.raw dl")  # raw state behind the toggle, as built-in cards
    assert page.errors == []  # type: ignore[attr-defined]


def save_picture(path: Path) -> None:
    """A 320x240 JPEG: a grey room with a pale face-sized square (what a camera saved)."""
    from PIL import Image, ImageDraw

    path.parent.mkdir(parents=True, exist_ok=True)
    picture = Image.new("RGB", (320, 240), (150, 150, 140))
    ImageDraw.Draw(picture).rectangle((120, 60, 200, 150), fill=(225, 190, 160))
    picture.save(path, format="JPEG")


async def test_the_last_frame_shows_on_its_card_with_the_faces_outlined(
    page: Page, runtime: TestRuntime, images_dir: Path
) -> None:
    runtime.device_list = desk()
    name = "reachy-20260101-120000-001.jpg"
    await asyncio.to_thread(save_picture, images_dir / name)
    faces = [{"x": 120, "y": 60, "width": 80, "height": 90, "looks_like": "Ada"}]
    receipts = [
        Receipt(
            device="reachy",
            tool="detect_faces",
            ok=True,
            started=1.0,
            duration=0.2,
            result=json.dumps({"path": name, "count": 1, "faces": faces, "width": 320, "height": 240}),
        ),
    ]
    assert runtime.activity is not None
    await runtime.activity.record(1, 3, receipts)
    await page.goto(f"/#login={runtime.login_codes.mint()}")
    frame = f"{card('reachy')} [data-widget-kind=image]"
    await page.wait_for_selector(f"{frame}[data-file='{name}'][data-boxes='1'] img")
    assert await page.eval_on_selector(f"{frame} img", "img => img.naturalWidth") == 320
    assert await page.get_attribute(f"{frame} .frame-box rect", "width") == "80"
    assert await page.text_content(f"{frame} .frame-box text") == "Ada"
    assert "1 found by detect_faces: Ada" in await page.inner_text(f"{frame} figcaption")
    assert "Ada" in (await page.get_attribute(f"{frame} img", "alt") or "")
    # The image came through the API with the token: the src is the page's own blob, not a path.
    assert (await page.get_attribute(f"{frame} img", "src") or "").startswith("blob:")
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    await page.locator(card("reachy")).screenshot(path=str(ARTIFACTS / "frame-with-face.png"))
    assert page.errors == []  # type: ignore[attr-defined]
