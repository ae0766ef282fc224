"""Who a launch waits behind, and when it gives up: the rule of :mod:`rosaos.processes.queue_behind`
over the manager's process records (the manager test runs it with real workers)."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime

import pytest

from rosaos.events.plan import FollowUp, FollowUpLaunch, Plan, PlanStep
from rosaos.processes.leases import Lease, LeaseRefused
from rosaos.processes.manager import ProcessInfo, ProcessProgress
from rosaos.processes.queue_behind import Refused, wait_behind

PLAN = Plan(steps=[PlanStep(device="lamp", tool="turn_on")], reply="Done.")


def holder(plan: Plan | None = PLAN, **changes: object) -> ProcessInfo:
    info = ProcessInfo(
        id=7,
        task="turn on the lamp",
        devices=["lamp"],
        state="running",
        plan=plan,
        started_at=datetime.now(UTC),
    )
    return info.model_copy(update=changes)


def refused_by(process_id: int = 7) -> LeaseRefused:
    message = f"lamp is held by process {process_id} ('turn on the lamp'); wait for it, or terminate_process({process_id})"
    return LeaseRefused(message, holders={"lamp": Lease("lamp", process_id, "turn on the lamp")})


async def ends_later(table: dict[int, ProcessInfo], state: str) -> None:
    await asyncio.sleep(0.2)
    table[7] = table[7].model_copy(update={"state": state})


async def test_waits_until_a_short_planned_holder_ends() -> None:
    table = {7: holder()}
    ending = asyncio.create_task(ends_later(table, "ok"))
    assert await wait_behind(refused_by(), table.__getitem__, bound=10) == [7]
    await ending


async def test_a_holder_stopped_meanwhile_cancels_the_waiting_launch() -> None:
    table = {7: holder()}
    ending = asyncio.create_task(ends_later(table, "terminated"))
    with pytest.raises(Refused, match="was stopped while this waited"):
        await wait_behind(refused_by(), table.__getitem__, bound=10)
    await ending


@pytest.mark.parametrize(
    "busy",
    [
        holder(plan=None),  # an LLM's process: the kernel decides, as before
        holder(progress=ProcessProgress(device="lamp", progress=1, at=datetime.now(UTC))),  # a long task
        holder(
            plan=PLAN.model_copy(
                update={
                    "then": FollowUp(
                        launches=[FollowUpLaunch(devices=["lamp"], summary="x", plan=PLAN)], summary="x"
                    )
                }
            )
        ),
    ],
    ids=["no-plan", "reports-progress", "has-follow-up"],
)
async def test_other_holders_are_refused_at_once_as_before(busy: ProcessInfo) -> None:
    with pytest.raises(Refused, match="is held by process 7"):
        await asyncio.wait_for(wait_behind(refused_by(), {7: busy}.__getitem__, bound=10), 1)


async def test_a_holder_that_outlasts_the_bound_is_refused_saying_how_long() -> None:
    with pytest.raises(Refused, match=r"still running after waiting 0\.3 s"):
        await wait_behind(refused_by(), {7: holder()}.__getitem__, bound=0.3)


async def test_a_refusal_that_is_not_only_about_holders_never_waits() -> None:
    refusal = LeaseRefused(
        "arm is not available now (status: down)\n" + str(refused_by()), holders=refused_by().holders
    )
    with pytest.raises(Refused, match="not available"):
        await asyncio.wait_for(wait_behind(refusal, {7: holder()}.__getitem__, bound=10), 1)
