"""Speaking back: the replies to the commands the voice front end sent are said by the robot."""

from __future__ import annotations

from typing import Any

from rosaos.frontends.voice.replies import ReplyFollower

COMMAND, CALLBACK, PROCESS = 10, 11, 3


class FakeKernel:
    """The updates stream and events of a kernel, as the follower reads them."""

    def __init__(self) -> None:
        self.updates: list[dict[str, Any]] = []
        self.handled: set[int] = set()

    def publish(self, kind: str, event_id: int, text: str = "", data: dict[str, Any] | None = None) -> None:
        self.updates.append(
            {
                "id": len(self.updates) + 1,
                "kind": kind,
                "event_id": event_id,
                "text": text,
                "data": data or {},
            }
        )

    async def last_update_id(self) -> int:
        return len(self.updates)

    async def updates_after(self, after: int) -> tuple[list[dict[str, Any]], int]:
        return self.updates[after:], len(self.updates)

    async def event(self, event_id: int) -> dict[str, Any]:
        return {"id": event_id, "handled": event_id in self.handled}

    # --- what a quick "turn on the kitchen light" looks like -----------------------------------------

    def command_handled(self) -> None:
        self.publish("event", COMMAND, "user said: turn on the kitchen light", {"kind": "user_said"})
        self.publish("process_launched", COMMAND, "process 3 launched", {"process_id": PROCESS})
        self.publish("kernel_reply", COMMAND, "On it: turn on the kitchen light.")
        self.handled.add(COMMAND)

    def callback_handled(self) -> None:
        payload = {"process_id": PROCESS, "status": "ok"}
        self.publish("event", CALLBACK, "process 3: ok", {"kind": "worker_callback", "payload": payload})
        self.publish("kernel_reply", CALLBACK, "Done: turn on the kitchen light.")
        self.handled.add(CALLBACK)


class Mouth:
    def __init__(self, robot: bool = True) -> None:
        self.said: list[str] = []
        self.robot = robot

    async def say(self, text: str) -> bool:
        self.said.append(text)
        return self.robot


def follower(kernel: FakeKernel, mouth: Mouth, heard: list[tuple[int, str, bool]], quiet: float = 0.8) -> Any:
    return ReplyFollower(kernel, mouth, lambda *reply: heard.append(reply), quiet_seconds=quiet)  # type: ignore[arg-type]


async def test_a_quick_task_is_answered_once_with_its_outcome() -> None:
    kernel, mouth, heard = FakeKernel(), Mouth(), []
    replies = follower(kernel, mouth, heard)
    await replies.start()
    replies.follow(COMMAND)
    kernel.command_handled()
    kernel.callback_handled()
    assert await replies.settle(timeout=5)
    assert mouth.said == ["Done: turn on the kitchen light."]
    assert heard == [(COMMAND, "Done: turn on the kitchen light.", True)]


async def test_a_slow_task_is_acknowledged_then_answered() -> None:
    kernel, mouth, heard = FakeKernel(), Mouth(), []
    replies = follower(kernel, mouth, heard, quiet=0.0)
    await replies.start()
    replies.follow(COMMAND)
    kernel.command_handled()
    await replies.poll()
    assert mouth.said == ["On it: turn on the kitchen light."]
    kernel.callback_handled()
    assert await replies.settle(timeout=5)
    assert mouth.said == ["On it: turn on the kitchen light.", "Done: turn on the kitchen light."]


async def test_updates_read_before_the_event_id_was_known_still_count() -> None:
    kernel, mouth, heard = FakeKernel(), Mouth(), []
    replies = follower(kernel, mouth, heard)
    await replies.start()
    kernel.command_handled()
    await replies.poll()  # the poller saw the event before POST /stt returned its id
    replies.follow(COMMAND)
    kernel.callback_handled()
    assert await replies.settle(timeout=5)
    assert mouth.said == ["Done: turn on the kitchen light."]


async def test_replies_to_other_front_ends_are_not_said() -> None:
    kernel, mouth, heard = FakeKernel(), Mouth(), []
    replies = follower(kernel, mouth, heard)
    await replies.start()
    kernel.publish("kernel_reply", 99, "someone else's answer")
    kernel.handled.add(99)
    replies.follow(COMMAND)
    kernel.command_handled()
    kernel.callback_handled()
    await replies.settle(timeout=5)
    assert "someone else's answer" not in mouth.said


async def test_without_a_robot_the_reply_is_still_reported() -> None:
    kernel, mouth, heard = FakeKernel(), Mouth(robot=False), []
    replies = follower(kernel, mouth, heard)
    await replies.start()
    replies.follow(COMMAND)
    kernel.command_handled()
    kernel.callback_handled()
    await replies.settle(timeout=5)
    assert heard == [(COMMAND, "Done: turn on the kitchen light.", False)]


async def test_settle_gives_up_on_a_process_that_never_ends() -> None:
    kernel, mouth, heard = FakeKernel(), Mouth(), []
    replies = follower(kernel, mouth, heard)
    await replies.start()
    replies.follow(COMMAND)
    kernel.command_handled()  # the process is launched but never calls back
    assert await replies.settle(timeout=0.3) is False
    assert replies.following == 1
