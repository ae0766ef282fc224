"""GET /processes, POST /processes/{id}/terminate and GET /devices, through the runtime."""

from __future__ import annotations

import httpx

from .kernel_support import AUTH, Process, TestRuntime


async def test_processes_lists_the_running_ones_with_their_devices(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.process_list = [
        Process(id=3, task="turn on the kitchen light", devices=["kitchen_light", "reachy"]),
        Process(id=4, task="play jazz", devices=["speaker"], state="ok"),
    ]
    response = await client.get("/processes", headers=AUTH)
    assert response.status_code == 200
    [process] = response.json()
    assert process["id"] == 3
    assert process["task"] == "turn on the kitchen light"
    assert process["devices"] == ["kitchen_light", "reachy"]
    assert process["state"] == "running"
    assert process["worker_pid"] == 4242


async def test_processes_accepts_plain_dicts_from_the_runtime(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    async def as_dicts(include_ended: bool = False) -> list[dict[str, object]]:
        return [{"id": 9, "task": "t", "devices": [], "state": "running"}]

    runtime.processes = as_dicts  # type: ignore[method-assign]
    assert (await client.get("/processes", headers=AUTH)).json()[0]["id"] == 9


async def test_terminate_ends_a_process(client: httpx.AsyncClient, runtime: TestRuntime) -> None:
    runtime.process_list = [Process(id=5, task="patrol the hallway", devices=["turtlebot"])]
    response = await client.post("/processes/5/terminate", headers=AUTH)
    assert response.status_code == 200
    assert response.json()["state"] == "terminated"
    assert runtime.terminated == [5]
    assert (await client.get("/processes", headers=AUTH)).json() == []


async def test_terminating_an_unknown_process_is_404_with_a_message(client: httpx.AsyncClient) -> None:
    response = await client.post("/processes/77/terminate", headers=AUTH)
    assert response.status_code == 404
    assert response.json()["detail"] == "no process 77: GET /processes lists the running ones"


async def test_devices_show_status_and_live_state(client: httpx.AsyncClient, runtime: TestRuntime) -> None:
    runtime.device_list[0]["state"]["on"] = True
    [device] = (await client.get("/devices", headers=AUTH)).json()
    assert device["name"] == "kitchen_light"
    assert device["driver"] == "tapo"
    assert device["concurrency"] == "exclusive"
    assert device["backend"] == "sim"
    assert device["status"] == "healthy"
    assert device["state"] == {"on": True, "brightness": 100}
    assert device["description"] == "Ceiling light in the kitchen"


async def test_devices_say_which_processes_hold_them_and_the_schema_says_so(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.device_list = [
        {"name": "vacuum", "driver": "ros", "concurrency": "exclusive", "status": "healthy", "held_by": [7]}
    ]
    [device] = (await client.get("/devices", headers=AUTH)).json()
    assert device["held_by"] == [7]
    assert device["state"] is None
    schema = (await client.get("/openapi.json")).json()["components"]["schemas"]["DeviceView"]
    assert "held_by" in schema["properties"]
    assert schema.get("additionalProperties") is not True  # every key is declared


async def test_ended_processes_are_listed_only_when_asked(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.process_list = [
        Process(id=1, task="done already", devices=[], state="ok"),
        Process(id=2, task="still going", devices=["lamp"]),
    ]
    running = (await client.get("/processes", headers=AUTH)).json()
    everything = (await client.get("/processes", params={"all": "true"}, headers=AUTH)).json()
    assert [p["id"] for p in running] == [2]
    assert [p["id"] for p in everything] == [1, 2]


async def test_the_emergency_stop_latches_until_reset(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    unlatched = {"latched": False, "reason": None, "time": None, "untold_hosts": []}
    assert (await client.get("/estop", headers=AUTH)).json() == unlatched
    stopped = (await client.post("/estop", json={"reason": "robot near the stairs"}, headers=AUTH)).json()
    assert (stopped["latched"], stopped["reason"]) == (True, "robot near the stairs")
    assert (stopped["terminated"], stopped["devices"], stopped["saved"]) == ([], [], True)
    latch = {key: stopped[key] for key in ("latched", "reason", "time", "untold_hosts")}
    assert (await client.get("/estop", headers=AUTH)).json() == latch
    assert (await client.post("/estop/reset", headers=AUTH)).json() == unlatched


async def test_the_emergency_stop_needs_the_token(client: httpx.AsyncClient) -> None:
    assert (await client.post("/estop")).status_code == 401
