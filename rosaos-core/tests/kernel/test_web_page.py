"""The web page: served publicly, useless without a login code, and working in a real browser.

The browser tests drive Debian's Chromium through Playwright against the app on a loopback port;
they are skipped where no Chromium is installed.
"""

from __future__ import annotations

import re
import shutil
from collections.abc import AsyncIterator
from datetime import UTC, datetime

import httpx
import pytest
from playwright.async_api import Page, async_playwright

from rosaos.kernel.event_store import EventStore
from rosaos.kernel.updates import UpdateStream

from .kernel_support import AUTH, Process, TestRuntime, eventually

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
STABLE_IDS = [
    "chat-input",
    "chat-send",
    "chat-log",
    "running",
    "events",
    "model-notice",
    "devices",
    "login-needed",
]


async def test_the_page_and_its_assets_are_served_without_a_token(client: httpx.AsyncClient) -> None:
    page = await client.get("/")
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    for element_id in STABLE_IDS:
        assert f'id="{element_id}"' in page.text
    for asset in re.findall(r'(?:src|href)="(/static/[^"]+)"', page.text):
        assert (await client.get(asset)).status_code == 200, asset


async def test_every_script_module_is_served(client: httpx.AsyncClient) -> None:
    app_js = (await client.get("/static/app.js")).text
    for module in re.findall(r'from "\./([^"]+)"', app_js):
        response = await client.get(f"/static/{module}")
        assert response.status_code == 200, module
        assert "javascript" in response.headers["content-type"]


async def test_the_page_is_locked_down_by_its_headers(client: httpx.AsyncClient) -> None:
    headers = (await client.get("/")).headers
    assert "script-src 'self'" in headers["content-security-policy"]
    assert "frame-ancestors 'none'" in headers["content-security-policy"]
    assert headers["referrer-policy"] == "no-referrer"


async def test_the_page_does_not_contain_the_token(client: httpx.AsyncClient) -> None:
    for path in ["/", "/static/app.js", "/static/session.js"]:
        assert AUTH["Authorization"].split()[1] not in (await client.get(path)).text


@pytest.fixture
async def browser_page(served: str) -> AsyncIterator[Page]:
    """A Chromium page whose relative URLs go to the served app; ``page.errors`` collects JS errors."""
    if CHROMIUM is None:
        pytest.skip("Chromium is not installed (apt install chromium)")
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        context = await browser.new_context(base_url=served)
        page = await context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        page.on("console", lambda message: errors.append(message.text) if message.type == "error" else None)
        page.errors = errors  # type: ignore[attr-defined]
        yield page
        await browser.close()


async def test_without_a_valid_login_code_the_page_says_where_to_get_one(
    browser_page: Page, runtime: TestRuntime
) -> None:
    p = browser_page
    used = runtime.login_codes.mint()
    assert runtime.login_codes.redeem(used)
    await p.goto(f"/#login={used}")
    await p.wait_for_selector("#login-error:has-text('already used')")
    # Said once, in words: the section above says how to get a fresh link.
    assert "`" not in await p.inner_text("#login-needed")
    assert "rosaos open" not in await p.inner_text("#login-error")
    assert "rosaos up" in await p.inner_text("#login-needed")
    assert "rosaos open" in await p.inner_text("#login-needed")  # how to get a fresh link
    assert await p.is_hidden("#app")
    # The notice is filled in by the page's first fetch, which may land after the error shows
    # (CI run 25 looked in between): wait for it, failing if it never shows.
    await p.wait_for_selector("#model-notice", state="visible", timeout=10_000)


async def test_chat_devices_processes_and_events_work_in_a_browser(
    browser_page: Page, runtime: TestRuntime, store: EventStore, updates: UpdateStream
) -> None:
    p = browser_page
    runtime.process_list = [Process(id=3, task="dim the kitchen light", devices=["kitchen_light"])]
    await p.goto(f"/#login={runtime.login_codes.mint()}")
    await p.wait_for_selector("#app", state="visible")
    assert "login=" not in p.url
    # The notice is filled in by the page's first fetch, which may land after #app shows.
    await p.wait_for_selector("#model-notice:has-text('No model is configured')")

    # Devices: a card per device, live state by key.
    light_on = '.device-card[data-device="kitchen_light"] [data-key="on"]'
    await p.wait_for_selector(f"{light_on}:text-is('false')")
    runtime.device_list[0]["state"]["on"] = True
    await p.wait_for_selector(f"{light_on}:text-is('true')")

    # Chat: typed text becomes an event; the stream shows it and the kernel's reply.
    await p.fill("#chat-input", "turn on the kitchen light")
    await p.press("#chat-input", "Enter")
    await p.wait_for_selector("#chat-log .msg-user:has-text('turn on the kitchen light')")
    event = await store.next_pending()
    assert event is not None
    assert (event.kind, event.source) == ("user_typed", "web")
    await updates.publish("kernel_reply", "The kitchen light is on.", event_id=event.id)
    await p.wait_for_selector("#chat-log .msg-kernel:has-text('The kitchen light is on.')")
    await p.wait_for_selector("#events li[data-kind='kernel_reply']", state="attached")
    assert await p.is_hidden("#events")  # the Debug view is closed until someone opens it
    assert await p.input_value("#chat-input") == ""

    # Running now: each running process with its devices, and a Stop button.
    row = '#running .run[data-process="3"]'
    await p.wait_for_selector(f"{row}:has-text('kitchen light')")
    await p.click(f'{row} button[data-terminate="3"]')
    await eventually(lambda: runtime.terminated == [3], message="the terminate request")
    await p.wait_for_selector(row, state="detached")
    assert p.errors == []  # type: ignore[attr-defined]


async def test_the_page_falls_back_to_polling_without_streaming(
    browser_page: Page, runtime: TestRuntime, updates: UpdateStream
) -> None:
    p = browser_page
    await p.add_init_script("delete window.TextDecoderStream")
    await p.goto(f"/#login={runtime.login_codes.mint()}")
    await p.wait_for_selector("#connection[data-state='polling']")
    await updates.publish("kernel_reply", "Polled reply.")
    await p.wait_for_selector("#chat-log .msg-kernel:has-text('Polled reply.')")
    assert p.errors == []  # type: ignore[attr-defined]


async def test_a_stop_latched_before_the_page_loads_shows_at_once_with_reason_and_time(
    browser_page: Page, runtime: TestRuntime
) -> None:
    # A kernel restarted while latched: the first GET /estop already says so.
    p = browser_page
    runtime.estop_reason = "robot near the stairs"
    runtime.estop_time = datetime(2025, 3, 4, 5, 6, 7, tzinfo=UTC)
    await p.goto(f"/#login={runtime.login_codes.mint()}")
    await p.wait_for_selector("#estop-banner", state="visible")
    assert await p.inner_text("#estop-reason") == "robot near the stairs"
    assert await p.get_attribute("#estop-time", "datetime") == "2025-03-04T05:06:07Z"
    assert "2025" in await p.inner_text("#estop-time")
    assert await p.is_hidden("#estop")

    runtime.estop_reason = runtime.estop_time = None  # reset elsewhere, e.g. `rosaos estop --reset`
    await p.wait_for_selector("#estop-banner", state="hidden")
    assert await p.is_visible("#estop")
    assert p.errors == []  # type: ignore[attr-defined]


async def test_hosts_the_stop_could_not_reach_are_named_on_the_page(
    browser_page: Page, runtime: TestRuntime
) -> None:
    p = browser_page
    runtime.estop_reason, runtime.estop_time = "pressed", datetime(2025, 3, 4, 5, 6, 7, tzinfo=UTC)
    runtime.untold_hosts = ["dog", "ghost"]
    await p.goto(f"/#login={runtime.login_codes.mint()}")
    await p.wait_for_selector("#estop-untold", state="visible")
    said = await p.inner_text("#estop-untold")
    assert "Not told of the emergency stop: dog, ghost" in said

    runtime.estop_reason = runtime.estop_time = None  # reset, but the dog's host has not heard it yet
    runtime.untold_hosts = ["dog"]
    await p.wait_for_selector("#estop-untold:has-text('Not told of the reset: dog.')")

    runtime.untold_hosts = []  # told at last
    await p.wait_for_selector("#estop-untold", state="hidden")
    assert p.errors == []  # type: ignore[attr-defined]
