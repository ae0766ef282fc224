"""The paper's demo on the web page, as a person sees it in Chromium (issue 24).

A kernel with the offline engine, real workers and the simulators: a TurtleBot 4 that must undock
and search for the person standing behind it, a PuppyPi placed elsewhere in the shared map
(``map_origin``), a Tapo lamp and a Spotify speaker. The page must keep the running search in view
with its follow-up, show no JSON or escaped text, drive the lamp from its card (a process like any
other: in Activity and in ``rosaos log``), refuse the card's controls while the emergency stop is
latched and say why, and draw the two robots apart with no label over another. The screenshots it
takes are the ones ``docs/web.md`` shows.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import re
import shutil
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio
from playwright.async_api import Page, async_playwright
from playwright.async_api import TimeoutError as PlaywrightTimeout

from rosaos.kernel.runtime import Kernel

from .cli_process import ROSAOS
from .e2e_support import device_state, eventually, running_kernel

pytestmark = pytest.mark.asyncio(loop_scope="module")

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DOCS = Path(__file__).resolve().parents[1] / "docs" / "web"
WAIT = 90_000  # ms: a busy machine runs the simulators slowly

SEARCH = "Undock the turtlebot, look around for a person, and when you find someone turn the lamp green"
SECOND = "Make the dog walk forward and play Here Comes the Sun"

WORLD = """
[kernel]
pool_size = 2

[devices.turtlebot]
driver = "ros"
profile = "turtlebot4"
description = "TurtleBot4 wheeled mobile robot with a camera and a charging dock"
sim = { docked = true, people = [{ x = 0.3, y = -2.5 }] }  # to its right: found late in the turn

[devices.dog]
driver = "ros"
profile = "puppypi"
description = "Hiwonder PuppyPi quadruped robot dog"
map_origin = { x = 2.5, y = 1.0, yaw = 1.5708 }  # switched on elsewhere in the lab, facing up the map

[devices.lamp]
driver = "tapo"
description = "TP-Link Tapo smart lamp in the lab"
sim = { on = false, hue = 0, saturation = 0, color_temp = 4000 }

[devices.spotify]
driver = "spotify"
description = "Music on the lab speaker"
sim = { is_playing = false, volume = 40, catalog = [{ track = "Here Comes the Sun", artist = "The Beatles", album = "Abbey Road", genre = "rock" }] }
"""

# Visible text a person should never read: a JSON object, an escaped character, markdown marks.
JSON_OBJECT = re.compile(r"\{\s*\"[^\"]*\"\s*:|\{\s*\}")
ESCAPED = re.compile(r"\\[nrtu\"\\/]")
MARKDOWN = re.compile(r"`|\*\*")


class Home:
    """The kernel and the folder of its ``rosaos.toml`` (for ``rosaos log``)."""

    def __init__(self, kernel: Kernel, path: Path) -> None:
        self.kernel = kernel
        self.path = path


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def home(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Home]:
    path = tmp_path_factory.mktemp("web-demo")
    async with running_kernel(path, WORLD) as kernel:
        yield Home(kernel, path)


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def page(home: Home) -> AsyncIterator[Page]:
    if CHROMIUM is None:
        pytest.skip("Chromium is not installed: ./scripts/test installs Debian's chromium package")
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        opened = await browser.new_page(viewport={"width": 1280, "height": 900})
        errors: list[str] = []
        opened.on("pageerror", lambda error: errors.append(str(error)))
        opened.on(
            "console",
            lambda message: errors.append(message.text) if _an_error(message.text, message.type) else None,
        )
        opened.errors = errors  # type: ignore[attr-defined]
        await opened.goto(home.kernel.login_link())
        await opened.wait_for_selector("#app", state="visible")
        await opened.wait_for_selector(f"{card('lamp')} .swatch-name:has-text('off (')")
        yield opened
        await browser.close()


def _an_error(text: str, kind: str) -> bool:
    """A console error, except Chromium's note on a refused control (423: the latch is set)."""
    return kind == "error" and "status of 423 (Locked)" not in text


def card(name: str) -> str:
    return f'.device-card[data-device="{name}"]'


async def say(page: Page, text: str, kernel: Kernel) -> None:
    # A device whose health check timed out (a loaded machine slows the ROS simulator) is not
    # granted to a process: wait, as a person would wait for the badge to turn healthy again.
    await eventually(lambda: _all_healthy(kernel), timeout=120)
    await page.fill("#chat-input", text)
    await page.press("#chat-input", "Enter")
    await page.wait_for_selector(f"#chat-log .msg-user:has-text({text!r})")


async def assert_readable(page: Page) -> None:
    """No visible text on the page is JSON, escaped or marked up."""
    text = await page.inner_text("body")  # rendered text only: closed Details and Debug are left out
    for pattern in (JSON_OBJECT, ESCAPED, MARKDOWN):
        found = pattern.search(text)
        assert found is None, (
            f"visible text matches {pattern.pattern}: …{text[max(0, found.start() - 80) : found.end() + 80]}…"
        )


async def test_the_running_search_is_in_view_with_its_follow_up(page: Page, home: Home) -> None:
    DOCS.mkdir(parents=True, exist_ok=True)
    await say(page, SEARCH, home.kernel)
    run = "#running .run:has(.run-meta:has-text('turtlebot'))"
    await page.wait_for_selector(run, timeout=WAIT)
    assert await page.evaluate("window.scrollY") == 0
    box = await page.locator(run).bounding_box()
    assert box is not None and box["y"] >= 0 and box["y"] + box["height"] <= 900, box
    assert (await page.inner_text(f"{run} .run-then")) == "Then: turn the lamp green"
    assert await page.is_visible(f"{run} button[data-terminate]")
    assert "rosaos-plan" not in await page.inner_text(f"{run} .run-task")
    await assert_readable(page)
    # For the picture: the search's own progress message rather than "Working…", if it says one
    # before it ends (it may not, on a slow machine; the picture is all that waits for it).
    search = f'#running .run[data-process="{await page.get_attribute(run, "data-process")}"]'
    with contextlib.suppress(PlaywrightTimeout):
        await page.wait_for_function(
            f"""() => !document.querySelector('{search}')
                 || document.querySelector('{search} .run-progress-text').textContent !== "Working…" """,
            timeout=20_000,
        )
    await page.wait_for_timeout(500)  # let the map and cards catch up
    await page.screenshot(path=str(DOCS / "search-1280.png"))
    assert page.errors == []  # type: ignore[attr-defined]


async def test_the_demo_ends_with_the_lamp_green_and_a_quiet_chat(page: Page, home: Home) -> None:
    await page.wait_for_selector(f"{card('lamp')} .swatch-name:text-matches('^green, ')", timeout=WAIT)
    # The paper asks this 3 s into the search; on a loaded test machine the ROS simulator answers
    # health checks late while it searches, so here it comes once the lamp is green.
    await say(page, SECOND, home.kernel)
    await page.wait_for_selector(
        f"{card('spotify')} [data-widget-key=is_playing] .widget-value:text-is('playing')", timeout=WAIT
    )
    await eventually(lambda: _none_running(home.kernel), timeout=WAIT / 1000)
    await page.wait_for_selector("#running-panel", state="hidden", timeout=WAIT)
    # Each call in Activity is a readable line: the lamp's result in the card's words.
    green = "#timeline .tl-call[data-tool='set_color_name']"
    await page.wait_for_selector(green, timeout=WAIT)
    assert re.search(r"Lamp: set color name \(green\)", await page.inner_text(f"{green} .tl-text"))
    assert re.fullmatch(r"on, green, \d+ %", await page.inner_text(f"{green} .tl-detail"))
    # The chat: what was said, and rosaOS's answers; no process bookkeeping.
    lines = await page.locator("#chat-log > li").all_inner_texts()
    assert not any(re.search(r"(?i)\bprocess \d+\b", line) for line in lines), lines
    await assert_readable(page)
    await page.wait_for_timeout(800)
    await page.screenshot(path=str(DOCS / "demo-1280.png"), full_page=True)
    await page.set_viewport_size({"width": 390, "height": 844})
    await page.wait_for_timeout(800)
    await page.screenshot(path=str(DOCS / "demo-390.png"), full_page=True)
    assert await page.evaluate("document.documentElement.scrollWidth") <= 390
    await page.set_viewport_size({"width": 1280, "height": 900})
    assert page.errors == []  # type: ignore[attr-defined]


async def test_two_robots_with_their_own_map_origin_are_drawn_apart_with_no_label_overlapping(
    page: Page,
) -> None:
    await page.wait_for_selector('#floor-map [data-robot="dog"]')
    centres = await page.evaluate(
        """() => Object.fromEntries([...document.querySelectorAll('#floor-map .map-robot')].map((g) => {
             const r = g.querySelector('.map-marker').getBoundingClientRect();
             return [g.dataset.robot, [r.x + r.width / 2, r.y + r.height / 2, r.width]];
           }))"""
    )
    (tx, ty, size), (dx, dy, _) = centres["turtlebot"], centres["dog"]
    assert ((tx - dx) ** 2 + (ty - dy) ** 2) ** 0.5 > 2 * size, centres
    boxes = await page.evaluate(
        """() => [...document.querySelectorAll('#floor-map .map-labels text')].map((t) => {
             const r = t.getBoundingClientRect();
             return [t.textContent, r.left, r.top, r.right, r.bottom];
           })"""
    )
    names = [box[0] for box in boxes]
    assert "turtlebot" in names and "dog" in names, names
    for index, (name, left, top, right, bottom) in enumerate(boxes):
        for other, oleft, otop, oright, obottom in boxes[index + 1 :]:
            apart = right <= oleft or oright <= left or bottom <= otop or obottom <= top
            assert apart, f"label {name!r} overlaps {other!r}: {boxes}"
    # One person, however often the search saw them; the summary counts people.
    assert await page.locator("#floor-map .map-person").count() == 1
    assert "1 person seen" in await page.inner_text("#map-summary")


async def test_the_lamp_cards_switch_turns_it_off_through_a_logged_process(page: Page, home: Home) -> None:
    switch = f"{card('lamp')} button[role=switch]"
    assert await page.get_attribute(switch, "aria-checked") == "true"
    await page.click(switch)
    await page.wait_for_selector(f"{card('lamp')} .swatch-name:has-text('off (')", timeout=WAIT)
    assert (await device_state(home.kernel, "lamp"))["on"] is False
    off = "#timeline .tl-process:has(.tl-call[data-tool='turn_off'])"
    await page.wait_for_selector(f"{off} .tl-callback[data-status=ok]", timeout=WAIT)
    assert "Power: off on the lamp" in await page.inner_text(f"{off} .tl-task")
    # ``rosaos log``, the real command: it asks this kernel, which runs on this test's event loop.
    command = await asyncio.create_subprocess_exec(
        str(ROSAOS),
        "log",
        "--config",
        str(home.path / "rosaos.toml"),
        "--device",
        "lamp",
        "--json",
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    out, err = await asyncio.wait_for(command.communicate(), timeout=120)
    assert command.returncode == 0, err.decode()
    entries = json.loads(out)
    calls = entries["entries"] if isinstance(entries, dict) else entries
    assert any(call["tool"] == "turn_off" and call["ok"] for call in calls), calls
    await assert_readable(page)


async def test_with_the_latch_set_the_cards_controls_are_refused_and_the_card_says_why(
    page: Page, home: Home
) -> None:
    await page.click("#estop")
    note = f"{card('lamp')} .control-note"
    await page.wait_for_selector(note, state="visible", timeout=WAIT)
    assert "emergency stop is latched" in await page.inner_text(note)
    await page.click(f"{card('lamp')} button[role=switch]")
    status = f"{card('lamp')} .control-status[data-kind=error]"
    await page.wait_for_selector(f"{status}:has-text('refused')", timeout=WAIT)
    assert "emergency stop is latched" in await page.inner_text(status)
    assert (await device_state(home.kernel, "lamp"))["on"] is False
    assert [p for p in await home.kernel.processes() if p.state == "running"] == []
    await assert_readable(page)
    await home.kernel.reset_emergency_stop()
    await page.wait_for_selector(note, state="hidden", timeout=WAIT)
    assert page.errors == []  # type: ignore[attr-defined]


async def _none_running(kernel: Kernel) -> bool:
    return not [p for p in await kernel.processes() if p.state == "running"]


async def _all_healthy(kernel: Kernel) -> bool:
    return all(device.status == "healthy" for device in await kernel.devices())
