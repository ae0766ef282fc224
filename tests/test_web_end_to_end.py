"""The web page on a real kernel: cards, map, camera frame and activity timeline in Chromium.

A kernel with the offline engine, a real worker, and the simulators of the built-in drivers (Tapo,
Spotify, Reachy Mini, TurtleBot 4 over rosbridge). The page is driven the way a person would:
typing in the chat and pressing the Yes button of a confirmation. Screenshots are written to
``artifacts/web/`` at the repository root (gitignored) for a person to look at.
"""

from __future__ import annotations

import shutil
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio
from playwright.async_api import Page, async_playwright

from rosaos.kernel.runtime import Kernel

from .e2e_support import running_kernel

pytestmark = pytest.mark.asyncio(loop_scope="module")

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts" / "web"
WAIT = 60_000  # ms: a busy CI machine runs the simulators slowly

WORLD = """
[kernel]
pool_size = 1
confirm_timeout = 60

[devices.turtlebot]
driver = "ros"
profile = "turtlebot4"
description = "TurtleBot 4 wheeled mobile robot with a camera"
confirm = ["move_distance"]
sim = { docked = false }

[devices.reachy]
driver = "reachy"

[devices.spotify]
driver = "spotify"
sim = { is_playing = false, volume = 40 }

[devices.kitchen_light]
driver = "tapo"
description = "Ceiling light in the kitchen"
sim = { on = false }
"""


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with running_kernel(tmp_path_factory.mktemp("web-kernel"), WORLD) as kernel:
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def page(kernel: Kernel) -> AsyncIterator[Page]:
    if CHROMIUM is None:
        pytest.skip("Chromium is not installed: ./scripts/test installs Debian's chromium package")
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        opened = await browser.new_page(viewport={"width": 1280, "height": 900})
        errors: list[str] = []
        opened.on("pageerror", lambda error: errors.append(str(error)))
        opened.on("console", lambda message: errors.append(message.text) if message.type == "error" else None)
        opened.errors = errors  # type: ignore[attr-defined]
        await opened.goto(kernel.login_link())
        await opened.wait_for_selector("#app", state="visible")
        yield opened
        await browser.close()


async def say(page: Page, text: str) -> None:
    await page.fill("#chat-input", text)
    await page.press("#chat-input", "Enter")
    await page.wait_for_selector(f"#chat-log .msg-user:has-text({text!r})")


def card(name: str) -> str:
    return f'.device-card[data-device="{name}"]'


async def test_a_chat_drives_every_card_the_map_and_the_timeline(page: Page) -> None:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    # Each card kind, from the drivers' own declarations.
    await page.wait_for_selector(f"{card('kitchen_light')} .swatch-name:has-text('off (')")
    await page.wait_for_selector(f"{card('reachy')} [data-widget-kind=head] svg[aria-label^='Head yaw']")
    await page.wait_for_selector(f"{card('spotify')} [data-widget-key=volume] .widget-value:text-is('40 %')")
    await page.wait_for_selector(f"{card('turtlebot')} [data-widget-kind=pose]:has-text('x 0.00 m')")

    await say(page, "set the kitchen light to red")
    await page.wait_for_selector(f"{card('kitchen_light')} .swatch-name:text-matches('^red, ')", timeout=WAIT)
    await say(page, "play some jazz")
    await page.wait_for_selector(
        f"{card('spotify')} [data-widget-key=is_playing] .widget-value:text-is('playing')", timeout=WAIT
    )
    assert await page.inner_text(f"{card('spotify')} [data-widget-key=track] .widget-value") not in ("", "—")

    # A camera frame, fetched behind the login and drawn on the card.
    await say(page, "take a picture")
    frame = f"{card('reachy')} [data-widget-kind=image]"
    await page.wait_for_selector(f"{frame}[data-file^='reachy-'] img", timeout=WAIT)
    assert await page.eval_on_selector(f"{frame} img", "img => img.naturalWidth") > 0
    assert (await page.inner_text(f"{frame} figcaption")).startswith("Last picture")

    # The map: the robot moves after a Yes in the timeline.
    marker = '#floor-map [data-robot="turtlebot"]'
    start = float(await page.get_attribute(marker, "data-x") or "nan")
    await say(page, "drive the turtlebot forward one meter")
    yes = "#timeline .tl-question button[data-answer='yes']"
    await page.wait_for_selector(yes, timeout=WAIT)
    assert "move" in (await page.inner_text("#timeline .tl-question-text")).lower()
    await page.click(yes)
    await page.wait_for_function(
        f"() => Number(document.querySelector('{marker}')?.dataset.x) >= {start + 0.9}", timeout=WAIT
    )
    await page.wait_for_selector(f"{marker} .map-trail", state="attached")  # a straight line has no height

    # The timeline of the chat: each process, its tool calls with results, and its end.
    picture = "#timeline .tl-process:has(.tl-call[data-tool='take_picture'])"
    await page.wait_for_selector(f"{picture} .tl-callback[data-status=ok]", timeout=WAIT)
    assert "Reachy: take picture" in await page.inner_text(f"{picture} .tl-call")
    drive = "#timeline .tl-process:has(.tl-call[data-tool='move_distance'])"
    await page.wait_for_selector(f"{drive} .tl-callback[data-status=ok]", timeout=WAIT)
    assert await page.locator("#timeline .tl-process").count() == 4

    await page.wait_for_timeout(1500)  # let the last frame and map redraw settle for the picture
    await page.screenshot(path=str(ARTIFACTS / "e2e-desktop.png"), full_page=True)
    await page.set_viewport_size({"width": 390, "height": 844})
    await page.wait_for_timeout(500)
    await page.screenshot(path=str(ARTIFACTS / "e2e-phone.png"), full_page=True)
    assert await page.evaluate("document.documentElement.scrollWidth") <= 390
    print(f"screenshots: {ARTIFACTS}")
    assert page.errors == []  # type: ignore[attr-defined]


async def test_a_long_search_shows_its_progress_while_a_second_request_finishes(
    page: Page, kernel: Kernel
) -> None:
    """The paper's concurrency, as a person sees it: the search's progress bar moves on in the
    timeline while the light, asked for after it, changes and its process ends."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    await say(page, "turtlebot, look around for someone")
    bar = "#timeline .tl-process .tl-progress:not([hidden]) .tl-progress-text"
    await page.wait_for_selector(bar, timeout=WAIT)
    await say(page, "set the kitchen light to blue")
    await page.wait_for_selector(
        f"{card('kitchen_light')} .swatch-name:text-matches('^blue, ')", timeout=WAIT
    )
    light = "#timeline .tl-process:has(.tl-call[data-tool='set_color_name'])"
    await page.wait_for_selector(f"{light} .tl-callback[data-status=ok]", timeout=WAIT)
    # The search still holds the turtlebot and still reports progress.
    running = [p for p in await kernel.processes() if p.state == "running"]
    assert [p.devices for p in running] and all("turtlebot" in p.devices for p in running), running
    assert await page.is_visible(bar)
    assert (await page.inner_text(bar)).strip()  # a percentage or a message, e.g. "turned 90°"
    task = await page.inner_text(f"#running .run[data-process='{running[0].id}'] .run-task")
    assert task == "Turtlebot, look around for someone." and "rosaos-plan" not in task
    await page.wait_for_timeout(1000)
    await page.screenshot(path=str(ARTIFACTS / "search-progress.png"), full_page=True)
    for process in running:
        await kernel.terminate(process.id)
    assert page.errors == []  # type: ignore[attr-defined]
