"""What the robots saw, asked later: "does the turtlebot see anyone?", then "where did you last see
someone?" names the nearest place and how long ago, "has anyone been in the living room today?",
and "show me" points to the picture, which the kernel serves.

The offline engine runs in a real kernel (event store, loop, workers) over the rosbridge
simulator, whose camera shows a person standing in the living room.
"""

from __future__ import annotations

from pathlib import Path

from .e2e_support import kernel_api, running_kernel
from .test_memory_llm_kernel import chat

WORLD = """
[devices.turtlebot]
driver = "ros"
description = "TurtleBot 4 wheeled mobile robot"
sim = { profile = "turtlebot4", x = 0.0, y = 1.0, docked = false, people = [{ x = 3.0, y = 1.0 }] }
"""


async def test_the_last_sighting_names_the_place_the_time_and_the_robot(tmp_path: Path) -> None:
    async with running_kernel(tmp_path, WORLD) as kernel, kernel_api(kernel) as api:
        assert (await chat(api, "where did you last see someone?"))[
            0
        ] == "I haven't seen anyone in the last 7 days."
        [nothing] = await chat(api, "show me")
        assert "I have no sighting with a picture in the last 7 days" in nothing, nothing
        await chat(api, "the living room is at x 3, y 0.5")
        await chat(api, "does the turtlebot see anyone?", count=2)  # launched, then done
        [last] = await chat(api, "where did you last see someone?")
        assert last == "In the living room, just now, seen by the turtlebot.", last
        [been] = await chat(api, "has anyone been in the living room today?")
        assert been.startswith("Yes: last in the living room"), been
        [shown] = await chat(api, "show me")
        prefix = "Here is the picture of the person in the living room, just now, seen by the turtlebot: "
        assert shown.startswith(prefix) and shown.endswith(" (on the page)."), shown
        picture = await api.get(shown.removeprefix(prefix).split(" ")[0])
        assert picture.status_code == 200 and picture.headers["content-type"] == "image/jpeg"
        [forgot] = await chat(api, "forget what you saw")
        assert forgot == "Forgotten: 1 sightings."
        assert (await chat(api, "where did you last see someone?"))[0].startswith("I haven't seen anyone")
