"""Faces the Reachy saw are sightings, and "show me" shows the picture on the page (issue 23).

The real kernel with the offline engine, a real worker and the Reachy simulator, whose camera sees
a real face (the NASA portrait of the Reachy plugin's fixtures). The Reachy stands on the floor map
at its ``map_origin``, next to "the living room" (a place a turtlebot saved before). "Reachy, is
there anyone in front of you?" runs ``detect_faces``; the face is kept as a sighting where the
Reachy stands, with its picture. On the page, "where did you last see someone?" names the place
and the Reachy, and "show me" puts the picture under the reply, fetched with the token. From the
shell, ``rosaos memory picture`` prints the file.
"""

from __future__ import annotations

import time
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio
from typer.testing import CliRunner

from rosaos.cli.root import app
from rosaos.kernel.runtime import Kernel
from rosaos.memory.store import MemoryStore, Place

from .e2e_support import eventually, kernel_api, running_kernel
from .test_memory_llm_kernel import chat
from .web_support import WAIT, logged_in_page, needs_chromium

pytestmark = [
    pytest.mark.e2e,
    pytest.mark.browser,
    pytest.mark.slow,
    pytest.mark.asyncio(loop_scope="module"),
]
FACE_PHOTO = Path(__file__).parents[1] / "plugins/rosaos-reachy/tests/fixtures/astronaut.jpg"

WORLD = f"""
[devices.reachy]
driver = "reachy"
description = "Reachy Mini on the living room shelf"
map_origin = {{ x = 1.0, y = 1.0 }}
sim = {{ camera_image = "{FACE_PHOTO}" }}
"""


@pytest_asyncio.fixture(loop_scope="module")
async def kernel(tmp_path: Path) -> AsyncIterator[Kernel]:
    # Saved by a turtlebot whose frame is the floor map's (no map_origin): 0.5 m from the Reachy.
    MemoryStore.open(tmp_path / "data").save_place(
        Place(name="the living room", device="turtlebot", frame="map", anchor="map:/maps/home.yaml",
              x=1.5, y=1.0, saved_at=time.time())
    )  # fmt: skip
    async with running_kernel(tmp_path, WORLD) as kernel:
        yield kernel


async def test_a_face_the_reachy_saw_is_named_and_show_me_shows_its_picture(
    kernel: Kernel, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    needs_chromium()
    async with kernel_api(kernel) as api:
        await chat(api, "reachy, is there anyone in front of you?")

        async def face_seen() -> list[dict[str, object]]:
            seen = (await api.get("/sightings")).json()["sightings"]
            return [s for s in seen if s["what"] == "face"]

        [face] = await eventually(face_seen, timeout=WAIT / 1000)
    assert (face["device"], face["frame"], face["x"], face["y"]) == ("reachy", "fixed", 0.0, 0.0)
    assert face["place"] == "the living room" and str(face["image"]).startswith("reachy-")

    async with logged_in_page(kernel) as opened:
        reply = await opened.ask("where did you last see someone?", "seen by the reachy")
        assert "In the living room" in await reply.inner_text()

        shown = await opened.ask("show me", "Here is the picture")
        text = await shown.inner_text()
        assert f"/sightings/{face['id']}/picture" in text and "face in the living room" in text, text
        picture = shown.locator(f"figure.sighting-picture[data-sighting='{face['id']}'] img")
        await picture.wait_for(timeout=WAIT)
        assert await picture.evaluate("img => img.naturalWidth") > 0
        assert (await picture.get_attribute("src") or "").startswith("blob:")  # fetched with the token
        assert not any(char in text for char in "{}[]"), text  # words, never raw JSON
    assert opened.errors == []

    monkeypatch.setenv("ROSAOS_DATA_DIR", str(tmp_path / "data"))
    printed = CliRunner().invoke(app, ["memory", "picture"])
    assert printed.exit_code == 0, printed.output
    assert Path(printed.output.strip()) == (tmp_path / "data" / "images" / str(face["image"])).resolve()
