"""Leases: exclusive devices go to one live process at a time, shared ones to any number."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import settings
from hypothesis import strategies as st
from hypothesis.stateful import Bundle, RuleBasedStateMachine, consumes, invariant, rule

from rosaos.devices.endpoints import DeviceEndpoint, DeviceStatus
from rosaos.drivers import Concurrency
from rosaos.processes.leases import LeaseRefused, LeaseTable


def endpoint(
    name: str,
    concurrency: Concurrency = "exclusive",
    *,
    always_attached: bool = False,
    status: DeviceStatus = "healthy",
    served: bool = True,
) -> DeviceEndpoint:
    return DeviceEndpoint(
        name=name,
        driver="testdevice",
        concurrency=concurrency,
        always_attached=always_attached,
        description=f"{name} for tests",
        prompt="",
        url=f"http://127.0.0.1:9/{name}/mcp" if served else None,
        token="t",
        status=status,
    )


def world(*endpoints: DeviceEndpoint) -> dict[str, DeviceEndpoint]:
    return {device.name: device for device in endpoints}


DEVICES = world(
    endpoint("kitchen_light"),
    endpoint("spotify"),
    endpoint("weather", "shared"),
)


def test_grant_returns_the_requested_devices_in_order() -> None:
    table = LeaseTable()
    assert table.acquire(1, "task", ["weather", "kitchen_light"], DEVICES) == ["weather", "kitchen_light"]
    assert table.held_by(1) == ["weather", "kitchen_light"]


def test_held_exclusive_device_is_refused_naming_holder_and_task() -> None:
    table = LeaseTable()
    table.acquire(3, "turn the light red", ["kitchen_light"], DEVICES)
    with pytest.raises(LeaseRefused) as refused:
        table.acquire(4, "turn the light blue", ["kitchen_light"], DEVICES)
    assert str(refused.value) == (
        "kitchen_light is held by process 3 ('turn the light red'); wait for it, or terminate_process(3)"
    )
    assert refused.value.holders["kitchen_light"].process_id == 3


def test_refusal_is_all_or_nothing() -> None:
    table = LeaseTable()
    table.acquire(1, "music", ["spotify"], DEVICES)
    with pytest.raises(LeaseRefused):
        table.acquire(2, "lights and music", ["kitchen_light", "spotify"], DEVICES)
    assert table.held_by(2) == []
    assert table.acquire(3, "light only", ["kitchen_light"], DEVICES) == ["kitchen_light"]


def test_shared_device_is_granted_to_two_processes() -> None:
    table = LeaseTable()
    table.acquire(1, "forecast", ["weather"], DEVICES)
    table.acquire(2, "forecast again", ["weather"], DEVICES)
    assert [lease.process_id for lease in table.holders()["weather"]] == [1, 2]


def test_always_attached_device_is_added_without_being_asked() -> None:
    devices = world(endpoint("reachy", "shared", always_attached=True), *DEVICES.values())
    table = LeaseTable()
    assert table.acquire(1, "light", ["kitchen_light"], devices) == ["kitchen_light", "reachy"]
    assert table.acquire(2, "just talk", [], devices) == ["reachy"]


def test_always_attached_device_with_a_pattern_goes_only_to_a_task_that_asks_for_it() -> None:
    # Issue 22: the Reachy's speaking tools, prompt and the prefix they force on every tool name
    # were a fifth of a light switch's process request, and its report reaches the user anyway.
    reachy = dataclasses.replace(
        endpoint("reachy", "shared", always_attached=True), attached_pattern=r"\b(say|tell)\b"
    )
    devices = world(reachy, *DEVICES.values())
    table = LeaseTable()
    assert table.acquire(1, "Turn on the kitchen light.", ["kitchen_light"], devices) == ["kitchen_light"]
    assert table.acquire(2, "Say good night", [], devices) == ["reachy"]
    # A task given no device can only speak, whatever its words: "The battery is low."
    assert table.acquire(5, "The battery is low.", [], devices) == ["reachy"]
    assert table.acquire(3, "Tell them the weather", ["weather"], devices) == ["weather", "reachy"]
    # Named by the kernel, it is granted whatever the task says.
    assert table.acquire(4, "Look left", ["reachy"], devices) == ["reachy"]


def test_always_attached_device_that_is_down_is_left_out() -> None:
    devices = world(endpoint("reachy", "shared", always_attached=True, status="unhealthy"), *DEVICES.values())
    assert LeaseTable().acquire(1, "light", ["kitchen_light"], devices) == ["kitchen_light"]


def test_unknown_device_lists_the_known_ones() -> None:
    with pytest.raises(
        LeaseRefused, match=r"unknown device 'oven'; the devices are: kitchen_light, spotify, weather"
    ):
        LeaseTable().acquire(1, "bake", ["oven"], DEVICES)


def test_device_that_is_not_served_is_refused_with_its_status() -> None:
    devices = world(endpoint("ros_robot", status="not implemented", served=False))
    with pytest.raises(LeaseRefused, match=r"ros_robot is not available now \(status: not implemented\)"):
        LeaseTable().acquire(1, "drive", ["ros_robot"], devices)


def test_release_frees_the_devices_and_is_idempotent() -> None:
    table = LeaseTable()
    table.acquire(1, "light", ["kitchen_light"], DEVICES)
    assert table.release(1) == ["kitchen_light"]
    assert table.release(1) == []
    assert table.holders() == {}
    assert table.acquire(2, "light again", ["kitchen_light"], DEVICES) == ["kitchen_light"]


def test_a_process_id_cannot_acquire_twice() -> None:
    table = LeaseTable()
    table.acquire(1, "light", ["kitchen_light"], DEVICES)
    with pytest.raises(ValueError, match="already holds leases"):
        table.acquire(1, "more", ["weather"], DEVICES)


MACHINE_DEVICES = world(
    endpoint("ex_a"),
    endpoint("ex_b"),
    endpoint("ex_c"),
    endpoint("sh_a", "shared"),
    endpoint("sh_b", "shared"),
    endpoint("ui", "shared", always_attached=True),
)
EXCLUSIVE = {name for name, device in MACHINE_DEVICES.items() if device.concurrency == "exclusive"}


class LeaseMachine(RuleBasedStateMachine):
    """Interleaves launches and endings (completion, crash, kill) and checks the lease invariants."""

    live = Bundle("live")

    def __init__(self) -> None:
        super().__init__()
        self.table = LeaseTable()
        self.granted: dict[int, set[str]] = {}
        self.ended: set[int] = set()
        self.next_id = 1

    @rule(target=live, requested=st.lists(st.sampled_from(sorted(MACHINE_DEVICES)), max_size=4))
    def launch(self, requested: list[str]) -> int:
        process_id, self.next_id = self.next_id, self.next_id + 1
        held_elsewhere = {name for devices in self.granted.values() for name in devices} & EXCLUSIVE
        try:
            granted = self.table.acquire(process_id, f"task {process_id}", requested, MACHINE_DEVICES)
        except LeaseRefused:
            # A refusal is only allowed when an exclusive device asked for is held by a live process.
            assert set(requested) & held_elsewhere
            self.ended.add(process_id)  # never started; acts like an ended id from here on
            return process_id
        assert not set(requested) & held_elsewhere
        assert set(granted) == set(requested) | {"ui"}
        self.granted[process_id] = set(granted)
        return process_id

    @rule(process_id=consumes(live), how=st.sampled_from(["ok", "crashed", "terminated", "timeout"]))
    def end(self, process_id: int, how: str) -> None:
        self.table.release(process_id)
        self.granted.pop(process_id, None)
        self.ended.add(process_id)

    @rule()
    def release_an_ended_process_again(self) -> None:
        for process_id in self.ended:
            assert self.table.release(process_id) == []

    @rule()
    def free_devices_are_grantable(self) -> None:
        held = {name for devices in self.granted.values() for name in devices}
        free = sorted(EXCLUSIVE - held)
        probe, self.next_id = self.next_id, self.next_id + 1
        assert set(self.table.acquire(probe, "probe", free, MACHINE_DEVICES)) == {*free, "ui"}
        self.table.release(probe)

    @invariant()
    def no_exclusive_device_has_two_live_holders(self) -> None:
        for name, leases in self.table.holders().items():
            if name in EXCLUSIVE:
                assert len(leases) == 1
            assert {lease.process_id for lease in leases} <= set(self.granted)

    @invariant()
    def table_matches_the_live_processes(self) -> None:
        for process_id, devices in self.granted.items():
            assert set(self.table.held_by(process_id)) == devices
        for process_id in self.ended:
            assert self.table.held_by(process_id) == []


# No example database: failing examples are cheap to find again and the state machine is small.
LeaseMachine.TestCase.settings = settings(
    max_examples=150, stateful_step_count=30, deadline=None, database=None
)
TestLeaseInvariants = LeaseMachine.TestCase
