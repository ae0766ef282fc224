"""The page of a running kernel in headless Chromium, logged in, for the end-to-end web tests.

One set-up for every test that asks the page something: skip without Chromium, open the login
link, wait for the app, and collect the page's JavaScript errors (a test ends by asserting there
were none).
"""

from __future__ import annotations

import shutil
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass, field

import pytest
from playwright.async_api import Locator, Page, async_playwright

from rosaos.kernel.runtime import Kernel

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
WAIT = 120_000
"""Milliseconds a page waits for a reply: a busy machine runs the simulators slowly."""


@dataclass
class OpenPage:
    """The logged-in page, and the JavaScript errors it raised so far."""

    page: Page
    errors: list[str] = field(default_factory=list)

    async def ask(self, text: str, reply_has: str) -> Locator:
        """Type ``text`` into the chat and wait for the kernel's reply that contains ``reply_has``."""
        await self.page.fill("#chat-input", text)
        await self.page.press("#chat-input", "Enter")
        reply = self.page.locator("#chat-log .msg-kernel", has_text=reply_has).last
        await reply.wait_for(timeout=WAIT)
        return reply


def needs_chromium() -> None:
    """Skip the test, saying how to fix it, where Chromium is not installed."""
    if CHROMIUM is None:
        pytest.skip("Chromium is not installed: ./scripts/test installs Debian's chromium package")


@asynccontextmanager
async def logged_in_page(kernel: Kernel) -> AsyncIterator[OpenPage]:
    """The kernel's page in headless Chromium (1280x900), opened with a login link."""
    needs_chromium()
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            opened = OpenPage(await browser.new_page(viewport={"width": 1280, "height": 900}))
            opened.page.on("pageerror", lambda error: opened.errors.append(str(error)))
            await opened.page.goto(kernel.login_link())
            await opened.page.wait_for_selector("#app", state="visible")
            yield opened
        finally:
            await browser.close()
