"""POST /devices/{name}/controls/{index}: a card control becomes a one-call process, or a clear refusal."""

from __future__ import annotations

import httpx

from rosaos.plugins import load_drivers

from .kernel_support import AUTH, Process, TestRuntime


def lamp_card() -> dict[str, object]:
    card = load_drivers().drivers["tapo"].spec.card
    assert card is not None
    return card.view()


def press(client: httpx.AsyncClient, index: int, value: object = None, name: str = "kitchen_light"):  # type: ignore[no-untyped-def]
    return client.post(f"/devices/{name}/controls/{index}", headers=AUTH, json={"value": value})


async def test_the_power_switch_launches_a_quiet_process_whose_plan_is_the_one_call(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.device_list[0]["card"] = lamp_card()
    response = await press(client, 0, False)
    assert response.status_code == 202, response.text
    body = response.json()
    assert (body["tool"], body["arguments"]) == ("turn_off", {})
    [process] = runtime.process_list
    assert process.devices == ["kitchen_light"] and body["process_id"] == process.id
    plan = process.plan  # a field of the launch, beside the task's words
    assert plan is not None and plan.quiet
    assert [(s.device, s.tool, s.args) for s in plan.steps] == [("kitchen_light", "turn_off", {})]
    assert process.task == "Power: off on the kitchen light (from its card on the web page)."


async def test_a_slider_sends_its_number_and_refuses_one_out_of_range(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.device_list[0]["card"] = lamp_card()
    assert (await press(client, 1, 40)).json()["arguments"] == {"brightness": 40}
    refused = await press(client, 1, 400)
    assert refused.status_code == 422
    assert "Brightness: 400 is outside 1-100" in refused.json()["detail"]
    unknown = await press(client, 2, "chartreuse")
    assert unknown.status_code == 422 and "choose one of" in unknown.json()["detail"]
    assert len(runtime.process_list) == 1  # only the good press launched anything


async def test_while_the_emergency_stop_is_latched_a_control_is_refused_and_says_why(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.device_list[0]["card"] = lamp_card()
    runtime.estop_reason = "robot too close to the stairs"
    response = await press(client, 0, True)
    assert response.status_code == 423
    assert "emergency stop is latched (robot too close to the stairs)" in response.json()["detail"]
    assert runtime.process_list == []


async def test_an_unknown_device_or_control_is_a_404_that_says_where_to_look(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.device_list[0]["card"] = lamp_card()
    assert "GET /devices" in (await press(client, 0, True, name="garage_door")).json()["detail"]
    missing = await press(client, 9, True)
    assert missing.status_code == 404 and "has 3 controls" in missing.json()["detail"]


async def test_a_robots_stop_first_stops_the_process_driving_it(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    card = load_drivers().drivers["ros"].spec.card
    assert card is not None
    runtime.device_list[0]["card"] = card.view()
    runtime.process_list = [Process(id=7, task="look around for someone", devices=["kitchen_light"])]
    stop = next(i for i, c in enumerate(card.controls) if c.label == "Stop")
    response = await press(client, stop)
    assert response.status_code == 202, response.text
    assert runtime.terminated == [7]
    assert runtime.process_list[-1].task.startswith("Stop on the kitchen light")
