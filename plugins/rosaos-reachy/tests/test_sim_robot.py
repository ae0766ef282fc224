"""The driver against the SDK's daemon in simulation (MuJoCo here): motion, speech and vision.

One robot for the module (the daemon takes seconds to start); each test opens its own client.
Tests that move the robot put it back to the bench's initial pose first.
"""

from __future__ import annotations

import asyncio
import math
import time
import wave
from collections.abc import AsyncIterator

import httpx
import pytest
import pytest_asyncio

from .reachy_support import BENCH_STATE, FACE_PHOTO, Robot, running_robot, sim_context

pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def robot(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Robot]:
    ctx = sim_context(tmp_path_factory.mktemp("rosaos-data"), camera_image=str(FACE_PHOTO), **BENCH_STATE)
    async with running_robot(ctx) as robot:
        yield robot


async def daemon_head(robot: Robot) -> dict[str, float]:
    """The head pose as the daemon itself reports it (REST, radians and metres → degrees and mm)."""
    assert robot.backend.daemon is not None
    async with httpx.AsyncClient(timeout=5) as http:
        pose = (await http.get(f"{robot.backend.daemon.url}/api/state/full")).json()["head_pose"]
    return {k: math.degrees(pose[k]) for k in ("roll", "pitch", "yaw")} | {k: pose[k] * 1000 for k in "xyz"}


async def test_the_simulation_is_mujoco_and_starts_in_the_bench_state(robot: Robot) -> None:
    state = await robot.call("get_state")
    assert state["mode"] == "sim: MuJoCo"
    assert {key: state[key] for key in BENCH_STATE} == {
        "head": {"x": 0.0, "y": 0.0, "z": 0.0, "roll": 0.0, "pitch": 0.0, "yaw": 0.0},
        "antennas": [0.0, 0.0],
        "body_yaw": 0.0,
        "awake": True,
        "last_spoken": "",
    }


async def test_look_left_turns_the_head_the_daemon_reports(robot: Robot) -> None:
    await robot.call("reset_head")
    result = await robot.call("look", direction="left")
    measured = await daemon_head(robot)
    assert measured["yaw"] == pytest.approx(30, abs=2)  # MuJoCo's physics, read from the daemon
    assert result["head"]["yaw"] == 30.0
    state = await robot.call("get_state")
    assert (state["head"]["yaw"], state["head"]["roll"], state["body_yaw"]) == (30.0, 0.0, 0.0)


async def test_look_with_angles_tilts_as_asked(robot: Robot) -> None:
    await robot.call("look", yaw=-20, pitch=10)
    measured = await daemon_head(robot)
    assert (measured["yaw"], measured["pitch"]) == (pytest.approx(-20, abs=2), pytest.approx(10, abs=2))


async def test_a_point_beside_the_robot_is_refused_with_the_fix(robot: Robot) -> None:
    message = await robot.error("look_at_point", x=0.0, y=1.0, z=0.0)
    assert "rotate_body first" in message


async def test_rotating_the_body_takes_the_head_along(robot: Robot) -> None:
    await robot.call("reset_head")
    result = await robot.call("rotate_body", degrees=30)
    assert (result["body_yaw"], result["head"]["yaw"]) == (30.0, 30.0)
    await robot.call("rotate_body", degrees=0)


async def test_an_emotion_returns_to_the_pose_it_started_from(robot: Robot) -> None:
    await robot.call("look", direction="left")
    before = (await robot.call("get_state"))["head"]
    result = await robot.call("play_emotion", name="nod", wait=True)
    assert "emotion yes" in result["message"] and "built-in" in result["message"]
    await robot.backend.motion.settle()
    assert (await robot.call("get_state"))["head"] == before


async def test_a_new_motion_interrupts_the_running_emotion(robot: Robot) -> None:
    started = await robot.call("play_emotion", name="sad")
    assert started["moving"] == "emotion sad"
    result = await robot.call("look", direction="right")
    assert result["moving"] is None
    assert result["head"]["yaw"] == -30.0


async def test_stop_motion_holds_the_dance_where_it_was(robot: Robot) -> None:
    await robot.call("dance")
    await asyncio.sleep(0.4)
    result = await robot.call("stop_motion")
    assert result["message"] == "stopped dance groove"
    assert (await robot.call("get_state"))["moving"] is None


async def test_speak_writes_espeak_audio_and_sets_last_spoken(robot: Robot) -> None:
    started = time.time()
    report = await robot.call("speak", text="Good morning to everyone")
    assert report["engine"] == "local"  # no cloud keys: espeak-ng
    assert report["output"] == "file"
    path = robot.ctx.data_dir / report["file"]
    with wave.open(str(path)) as wav:
        seconds = wav.getnframes() / wav.getframerate()
    assert seconds == pytest.approx(report["seconds"], abs=0.01) and seconds > 0.5
    assert report["speaking_until"] == pytest.approx(started + seconds, abs=1.0)
    state = await robot.call("get_state")
    assert state["last_spoken"] == "Good morning to everyone"
    assert state["speaking"] is True and state["speaking_until"] == report["speaking_until"]


LONG_ANSWER = (
    "Here is everything I know about the weather this week, day by day, starting with Monday, "
    "which will be cloudy in the morning and sunny later."
)


async def test_stop_speaking_cuts_off_a_long_answer(robot: Robot) -> None:
    report = await robot.call("speak", text=LONG_ANSWER)
    assert report["seconds"] > 5 and (await robot.call("get_state"))["speaking"] is True
    stopped = await robot.call("stop_speaking")
    assert stopped == {"stopped": True, "cut_off": LONG_ANSWER}
    state = await robot.call("get_state")
    assert state["speaking"] is False and state["speaking_until"] is None
    assert (await robot.call("stop_speaking"))["stopped"] is False  # nothing left to stop


async def test_speak_with_interrupt_replaces_the_sentence_being_spoken(robot: Robot) -> None:
    await robot.call("speak", text=LONG_ANSWER)
    report = await robot.call("speak", text="Sorry, go ahead.", interrupt=True)
    assert report["cut_off"] == LONG_ANSWER and report["interrupted"] is False
    assert report["speaking_until"] == pytest.approx(time.time() + report["seconds"], abs=1.0)
    state = await robot.call("get_state")
    assert state["last_spoken"] == "Sorry, go ahead." and state["speaking"] is True
    await robot.call("stop_speaking")


async def face_forward(robot: Robot) -> None:
    """Body and head facing forward: the sim camera then sees the photo centred."""
    await robot.call("rotate_body", degrees=0)
    await robot.call("reset_head")


async def test_take_picture_then_detect_faces_finds_the_face(robot: Robot) -> None:
    await face_forward(robot)
    picture = await robot.call("take_picture")
    assert picture["simulated"] is True and "simulated" in picture["note"]
    assert (robot.ctx.images_dir / picture["path"]).is_file()
    found = await robot.call("detect_faces", path=picture["path"])
    assert found["count"] == 1
    x, y = found["faces"][0]["center"]
    assert -1 < x < 0 and -1 < y < 0  # the astronaut's face is up and left of the photo's centre


async def test_look_at_face_brings_the_face_to_the_centre(robot: Robot) -> None:
    await face_forward(robot)
    result = await robot.call("look_at_face")
    assert result["head"]["yaw"] > 0 and result["head"]["pitch"] < 0  # up and to the left
    found = await robot.call("detect_faces")
    x, y = found["faces"][0]["center"]
    assert abs(x) < 0.15 and abs(y) < 0.15


async def test_a_remembered_face_is_recognised_and_can_be_forgotten(robot: Robot) -> None:
    await face_forward(robot)
    assert "remembered Eileen" in await robot.call("remember_face", name="Eileen")
    found = await robot.call("detect_faces")
    assert found["faces"][0]["looks_like"] == "Eileen" and found["remembered"] == ["Eileen"]
    faces_dir = robot.ctx.data_dir / "drivers" / "reachy" / "faces" / "Eileen"
    assert any(faces_dir.glob("*.png"))
    assert await robot.call("forget_face", name="Eileen") == "forgot Eileen"
    assert (await robot.call("detect_faces"))["faces"][0]["looks_like"] is None


async def test_describe_image_without_a_model_describes_locally_and_says_a_model_would_say_more(
    robot: Robot,
) -> None:
    await face_forward(robot)
    picture = await robot.call("take_picture")
    answer = await robot.call("describe_image", path=picture["path"])
    faces = (await robot.call("detect_faces", path=picture["path"]))["count"]
    assert faces >= 1, "the simulated camera faces the photo of a person"
    seen = f"{faces} face{'s' if faces != 1 else ''}"
    assert answer.startswith(f"Described on this computer, without a vision model: I see {seen}")
    assert "Main colours:" in answer and "brightness" in answer
    assert "A vision model would say more" in answer and "GROQ_API_KEY" in answer


async def test_a_picture_outside_the_images_directory_is_refused(robot: Robot) -> None:
    message = await robot.error("detect_faces", path="../../etc/passwd")
    assert "outside the images directory" in message


TOOLS = {
    "get_state", "speak", "stop_speaking", "look", "look_at_point", "reset_head", "rotate_body", "move_antennas",
    "play_emotion", "list_emotions", "dance", "stop_motion", "wake_up", "sleep", "take_picture",
    "describe_image", "detect_faces", "remember_face", "forget_face", "analyze_face", "look_at_face",
    "set_listening", "follow_face",
}  # fmt: skip


async def test_the_server_offers_the_robot_tools_each_annotated(robot: Robot) -> None:
    async with robot.client() as client:
        tools = await client.list_tools()
    assert {tool.name for tool in tools} == TOOLS
    for tool in tools:
        hints = tool.annotations
        assert hints is not None and hints.read_only_hint is not None and hints.destructive_hint is not None
        assert hints.destructive_hint is (tool.name == "forget_face"), tool.name
