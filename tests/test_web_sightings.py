"""After the paper's demo, "where did you last see someone?" names the place and the time, and the
page's floor map shows that sighting where it was, with the named place beside it (issue 23).

The real kernel with the offline engine, real workers and the simulators: a docked TurtleBot 4 with
a person standing behind it, and a Tapo lamp. The living room is named first ("the living room is
at x 0.5, y -2"); the paper's sentence then undocks the robot, searches until it finds the person,
and turns the lamp green. Chromium opens the page with a login link and asks the question.
"""

from __future__ import annotations

import math
from collections.abc import AsyncIterator
from pathlib import Path

import httpx
import pytest
import pytest_asyncio

from rosaos.kernel.runtime import Kernel

from .e2e_support import device_state, eventually, kernel_api, running_kernel
from .test_memory_llm_kernel import chat
from .web_support import WAIT, logged_in_page, needs_chromium

pytestmark = [pytest.mark.e2e, pytest.mark.browser, pytest.mark.asyncio(loop_scope="module")]
PERSON = (0.3, -2.5)
DEMO = "Undock the turtlebot, look around for a person, and when you find someone turn the lamp green"

WORLD = f"""
[devices.turtlebot]
driver = "ros"
profile = "turtlebot4"
description = "TurtleBot4 wheeled mobile robot with a camera and a charging dock"
sim = {{ docked = true, people = [{{ x = {PERSON[0]}, y = {PERSON[1]} }}] }}

[devices.lamp]
driver = "tapo"
description = "TP-Link Tapo smart lamp in the lab"
sim = {{ on = false, hue = 0, saturation = 0, color_temp = 4000 }}
"""


@pytest_asyncio.fixture(loop_scope="module")
async def kernel(tmp_path: Path) -> AsyncIterator[Kernel]:
    async with running_kernel(tmp_path, WORLD) as kernel:
        yield kernel


async def _demo_done(kernel: Kernel, api: httpx.AsyncClient) -> bool:
    lamp = await device_state(kernel, "lamp")
    running = [p for p in (await api.get("/processes")).json() if p["state"] == "running"]
    return bool(lamp.get("on") and lamp.get("hue") == 120 and not running)


async def test_the_last_sighting_is_named_in_chat_and_drawn_on_the_map(kernel: Kernel) -> None:
    needs_chromium()
    async with kernel_api(kernel) as api:
        [saved] = await chat(api, "the living room is at x 0.5, y -2")
        assert "living room" in saved, saved
        await chat(api, DEMO)
        await eventually(lambda: _demo_done(kernel, api), timeout=WAIT / 1000)
    async with logged_in_page(kernel) as opened:
        page = opened.page
        reply = await opened.ask("where did you last see someone?", "seen by")
        answer = await reply.inner_text()
        assert "In the living room" in answer and "seen by the turtlebot" in answer, answer
        assert "just now" in answer or "minute" in answer, answer

        # The map: the sighting where the person stood, named by the place; the place itself.
        sighting = page.locator("#floor-map .map-sighting").first
        await sighting.wait_for(timeout=WAIT)
        assert await sighting.get_attribute("data-device") == "turtlebot"
        assert "living room" in (await sighting.get_attribute("data-place") or "")
        x, y = (
            float(await sighting.get_attribute("data-x") or "nan"),
            float(await sighting.get_attribute("data-y") or "nan"),
        )
        assert math.hypot(x - PERSON[0], y - PERSON[1]) < 0.6, (x, y)
        title = await sighting.locator("title").text_content() or ""
        assert title.startswith("person in the living room, ") and "seen by turtlebot" in title, title
        assert await page.locator('#floor-map .map-place[data-place*="living room"]').count() == 1
        summary = await page.inner_text("#map-summary")
        assert "Last seen: person in the living room" in summary, summary
        await page.locator("#map-panel").screenshot(path=str(Path(kernel.config.data_dir).parent / "map.png"))
    assert opened.errors == []
