"""The page renames and deletes named places (issue 23): the list under the floor map has Rename and
Delete, the kernel refuses a taken or empty name with its reason shown, and what the page changed is
what ``rosaos places --json`` then lists (the CLI reads the same memory file)."""

from __future__ import annotations

import json
import time

import pytest
from playwright.async_api import Page
from typer.testing import CliRunner

from rosaos.cli.root import app
from rosaos.memory.store import Place

from .kernel_support import TestRuntime
from .web_support import desk


def place(name: str, x: float, y: float) -> Place:
    return Place(
        name=name, device="turtlebot", frame="odom", anchor="odom:turtlebot:1", x=x, y=y, saved_at=time.time()
    )


async def test_the_page_renames_and_deletes_places_and_the_cli_lists_the_result(
    page: Page, runtime: TestRuntime, monkeypatch: pytest.MonkeyPatch
) -> None:
    runtime.device_list = desk()
    runtime.memory.save_place(place("the kitchen", 2.0, 1.0))
    runtime.memory.save_place(place("the hall", -1.0, 0.5))
    await page.goto(f"/#login={runtime.login_codes.mint()}")
    kitchen = '#places li[data-place="the kitchen"]'
    await page.wait_for_selector(kitchen)
    await page.wait_for_selector('#floor-map .map-place[data-place="the kitchen"]')

    await page.click(f'{kitchen} button[data-action="rename"]')
    new_name = page.get_by_label("New name for the kitchen")
    await new_name.fill("The Hall")
    await page.click(f"{kitchen} button[type=submit]")
    status = page.locator("#places-status")
    await status.filter(has_text="already a place called").wait_for()
    assert await status.get_attribute("data-kind") == "error"
    await new_name.fill("   ")
    await page.click(f"{kitchen} button[type=submit]")
    await status.filter(has_text="the new name is empty").wait_for()
    assert {p.name for p in runtime.memory.places()} == {"the kitchen", "the hall"}  # nothing changed

    await new_name.fill("the galley")
    await page.click(f"{kitchen} button[type=submit]")
    await page.wait_for_selector('#places li[data-place="the galley"]')
    await page.wait_for_selector('#floor-map .map-place[data-place="the galley"]')
    await page.click('#places li[data-place="the hall"] button[data-action="delete"]')
    await status.filter(has_text="Deleted the hall.").wait_for()
    await page.wait_for_selector('#places li[data-place="the hall"]', state="detached")
    await page.wait_for_selector('#floor-map .map-place[data-place="the hall"]', state="detached")

    monkeypatch.setenv("ROSAOS_DATA_DIR", str(runtime.memory.path.parent))
    listed = CliRunner().invoke(app, ["places", "--json"])
    assert listed.exit_code == 0, listed.output
    assert [(p["name"], p["x"], p["y"], p["anchor"]) for p in json.loads(listed.output)] == [
        ("the galley", 2.0, 1.0, "odom:turtlebot:1")
    ]
    # The browser logs each refused request (409, 422) as a console error; nothing else may fail.
    assert [e for e in page.errors if "status of 409" not in e and "status of 422" not in e] == []  # type: ignore[attr-defined]
