"""Worker main, ``python -m rosaos.processes.worker``: runs process agents, one job at a time.

A worker is long-lived so the pool can keep it warm: the heavy imports (pydantic-ai, FastMCP)
happen once, at start-up. The protocol with the pool is one JSON object per line:

- stdin, pool to worker: a :class:`~rosaos.processes.jobs.WorkerJob`.
- stdout, worker to pool: the typed messages of :mod:`rosaos.processes.protocol`: ``ready`` once
  the imports are done, ``progress`` for each MCP progress notification a device tool sends while
  a job runs, ``done`` with the :class:`~rosaos.processes.jobs.WorkerCallback` when it ends, or
  ``rejected`` for a line that is not a valid job. ``done`` is the only way a process's end
  reaches the kernel.

stdout carries protocol lines only: the real stdout is kept for them and fd 1 is pointed at
stderr, so a stray ``print`` in a library cannot corrupt the protocol. Logs go to stderr.
The worker exits when stdin closes (the pool is gone); if a job is running then, it is cancelled
and its devices get ``safe_stop`` first, so no process actuates without a kernel.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import sys
import time
from collections.abc import Awaitable, Callable, Sequence
from typing import IO, Any

import httpx
from fastmcp import Client
from fastmcp.client.transports import StreamableHttpTransport
from pydantic import ValidationError
from pydantic_ai import Agent, UsageLimitExceeded, capture_run_messages
from pydantic_ai.mcp import MCPToolset
from pydantic_ai.messages import ModelMessage, ModelResponse
from pydantic_ai.models import Model
from pydantic_ai.toolsets import AbstractToolset
from pydantic_ai.usage import UsageLimits

from rosaos.confirmations.confirming import ConfirmationDeclined, ConfirmingToolset, KernelAsker
from rosaos.events.callback import ProcessStatus, WorkerCallback
from rosaos.fastmcp_spans import spans_off
from rosaos.models.process_model import LocalPlanModel
from rosaos.models.select import ModelError, build_model
from rosaos.models.tool_schemas import CompactToolsModel
from rosaos.processes.final_call import FINAL_CALL_MODEL, FinalCallModel
from rosaos.processes.jobs import GrantedDevice, WorkerJob
from rosaos.processes.keepalive import DeadlineToolset, DeviceLink, keepalives, owner_headers
from rosaos.processes.lease_guard import LeaseGuardModel
from rosaos.processes.listed_tools import ListedToolset
from rosaos.processes.outcome import judge
from rosaos.processes.plan_runner import run_plan
from rosaos.processes.prompts import job_text, process_system_prompt, tool_prefix
from rosaos.processes.protocol import Done, Progress, Ready, Rejected, encode
from rosaos.processes.recording import RecordingToolset
from rosaos.processes.tool_calls import ToolCallLog, observed
from rosaos.processes.tool_offer import offered_tools
from rosaos.processes.vision import ImageFallbackModel, image_budget_for, image_headers
from rosaos.receipts import Receipt
from rosaos.tls import shared_context

log = logging.getLogger("rosaos.processes.worker")

CONNECT_TIMEOUT = 10.0
"""Seconds to open an MCP session with one granted device."""
TRUSTED_FOR = 60.0
"""Seconds a kept device session is used without a check while its server is the same one (well
under the server's 30-minute idle expiry of a session)."""
ORPHAN_STOP_TIMEOUT = 3.0
"""Seconds each device's ``safe_stop`` may take when the kernel died under a running job."""
LINE_LIMIT = 16 * 1024 * 1024
"""Largest job line accepted (device prompts make jobs a few KiB; this is only a guard)."""


class DeviceUnreachable(Exception):
    """A granted device whose MCP server could not be reached; the message names it and its URL."""


def process_model(job: WorkerJob) -> Model:
    """The process agent's model: the offline plan runner, the configured LLM, or a routing of both.

    With no model configured, :class:`~rosaos.models.process_model.LocalPlanModel` executes the
    plan the offline engine wrote into the task. With one configured and ``prefer_local``, a
    planned task still runs locally and anything else goes to the LLM.
    """
    from rosaos.models.routing import process_model_for

    spec = job.model
    llm = None if spec.model is None else build_model(spec)
    return process_model_for(job.plan, llm, spec.prefer_local, spec.language)


async def run_job(job: WorkerJob) -> WorkerCallback:
    """Run one process agent to completion and describe how it ended. Never raises."""
    status: ProcessStatus = "ok"
    output: str | None = None
    error: str | None = None
    calls = ToolCallLog()
    receipts: list[Receipt] = []  # every tool call, for the activity log (processes/recording.py)
    with capture_run_messages() as messages:
        try:
            async with asyncio.timeout(job.timeout) as deadline:
                output = await _run_agent(job, calls, receipts)
        except TimeoutError:
            if not deadline.expired():
                log.exception("process %d failed", job.process_id)
                status, error = "error", "a tool or model call timed out; try again, or check the device"
            else:
                status = "timeout"
                error = f"the process ran past its timeout of {job.timeout:g} s and was stopped"
        except ConfirmationDeclined as declined:  # a person said no: the process ends, nothing done
            status, error = "terminated", str(declined)
        except UsageLimitExceeded:
            status = "error"
            error = (
                f"the process used its limit of {job.request_limit} model requests without finishing; "
                "split the task into smaller ones, or raise [kernel] request_limit"
            )
        except Exception as failure:
            log.exception("process %d failed", job.process_id)
            status, error = "error", describe_error(failure)
    # Success is the devices' word, not the model's (processes/outcome.py, issue 22).
    status, error = judge(
        status, error, task=job.task, devices=job.devices, calls=calls, model_ran=bool(messages)
    )
    requests, tool_calls = count_usage(messages)
    if not messages:  # a plan run without an agent (processes/plan_runner.py): no model requests
        tool_calls = len(calls.calls)
    return WorkerCallback(
        process_id=job.process_id,
        status=status,
        output=output,
        error=error,
        task=job.task,
        plan=job.plan,
        then=job.then,
        model_requests=requests,
        tool_calls=tool_calls,
        receipts=receipts,
    )


class DeviceSessions:
    """MCP sessions to devices, kept open across the jobs of this worker.

    Opening a session and listing its tools cost more than the tool call itself; a warm worker
    that keeps them answers the next job on the same device at once. A kept session may be stale:
    a restarted host keeps its URL but knows no earlier session, and a server ends a session idle
    for 30 minutes. It is trusted without a check when the kernel names the same server process
    (``server_epoch``) as when it was opened or last checked and it was used within
    :data:`TRUSTED_FOR` seconds; otherwise one ``tools/list`` round trip (~4 ms, a third of an
    offline command; MCP ``ping`` is not served by our FastMCP version) checks it first, and it is
    reopened if its device went away. A session that failed in a job is closed (:meth:`forget`).
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._open: dict[tuple[str, str], MCPToolset[Any]] = {}
        self._images: dict[tuple[str, str], int | None] = {}
        self._checked: dict[tuple[str, str], tuple[str | None, float]] = {}
        """Per session: the server epoch it was last known good under, and when (``clock``)."""
        self._clock = clock

    async def toolset(self, device: GrantedDevice, images: int | None = None) -> MCPToolset[Any]:
        key = (device.url, device.token)
        kept = self._open.get(key)
        if kept is not None and self._images.get(key) != images:  # the images header is per session
            await self._close(key)
            kept = None
        if kept is not None and self._trusted(key, device.server_epoch):
            self._checked[key] = (device.server_epoch, self._clock())
            return kept
        if kept is not None:
            try:
                async with asyncio.timeout(CONNECT_TIMEOUT):
                    await kept.client.list_tools()
                self._checked[key] = (device.server_epoch, self._clock())
                return kept
            except Exception:
                await self._close(key)
        toolset = await _connect(device, images)
        self._open[key], self._images[key] = toolset, images
        self._checked[key] = (device.server_epoch, self._clock())
        return toolset

    def _trusted(self, key: tuple[str, str], epoch: str | None) -> bool:
        checked = self._checked.get(key)
        if epoch is None or checked is None:
            return False
        return checked[0] == epoch and self._clock() - checked[1] < TRUSTED_FOR

    async def forget(self, devices: Sequence[GrantedDevice]) -> None:
        """Close the sessions of a job that failed: the next job starts from fresh ones."""
        for device in devices:
            await self._close((device.url, device.token))

    async def close_all(self) -> None:
        for key in list(self._open):
            await self._close(key)

    async def _close(self, key: tuple[str, str]) -> None:
        self._images.pop(key, None)
        self._checked.pop(key, None)
        toolset = self._open.pop(key, None)
        if toolset is not None:
            with contextlib.suppress(Exception):
                await toolset.__aexit__(None, None, None)


SESSIONS = DeviceSessions()


class ProgressRelay:
    """Passes a device tool's MCP progress notifications to the pool as :class:`Progress` lines.

    Device sessions outlive jobs, so the relay, not the session, knows which process runs now.
    """

    def __init__(self) -> None:
        self.send: Callable[[Progress], None] | None = None
        self.process_id: int | None = None

    def handler(self, device: str) -> Callable[[float, float | None, str | None], Awaitable[None]]:
        """The ``progress_handler`` for ``device``'s client."""

        async def relay(progress: float, total: float | None, message: str | None) -> None:
            if self.send is not None and self.process_id is not None:
                self.send(
                    Progress(
                        process_id=self.process_id,
                        device=device,
                        progress=progress,
                        total=total,
                        message=(message or "")[:500],
                    )
                )

        return relay


PROGRESS = ProgressRelay()


async def _run_agent(job: WorkerJob, calls: ToolCallLog, receipts: list[Receipt] | None = None) -> str:
    # Keepalives run for the whole job: a host stops an armed device whose owner goes quiet.
    async with keepalives(job.devices) as links:
        try:
            return await _run_agent_linked(job, calls, receipts, links)
        finally:
            lost = [link.device for link in links.values() if link.losses]
            if lost:  # a session that lived through a silent network is not to be trusted again
                await SESSIONS.forget(lost)


async def _run_agent_linked(
    job: WorkerJob, calls: ToolCallLog, receipts: list[Receipt] | None, links: dict[str, DeviceLink]
) -> str:
    model = process_model(job)
    prefixed = len(job.devices) > 1
    recorded = receipts if receipts is not None else []
    try:
        toolsets: list[AbstractToolset[Any]] = []
        asker = KernelAsker(job.kernel_url, job.kernel_token, job.process_id)
        for device in job.devices:
            session = await SESSIONS.toolset(device, image_budget_for(job.model, model))
            bounded = DeadlineToolset(wrapped=session, link=links.get(device.name))
            # The offline plan runner calls the tools its plan names; only a model is offered less.
            offered = (
                bounded if isinstance(model, LocalPlanModel) else offered_tools(bounded, device, job.task)
            )
            guarded = ConfirmingToolset(offered, device=device.name, rule=device.confirm, asker=asker)
            toolset = observed(
                RecordingToolset(guarded, device=device.name, receipts=recorded), device.name, calls
            )
            toolsets.append(toolset.prefixed(tool_prefix(device.name)) if prefixed else toolset)
        if isinstance(model, LocalPlanModel) and job.plan is not None:
            return await run_plan(job.plan, toolsets, model, model.language)
        if not isinstance(model, LocalPlanModel):
            granted = [device.name for device in job.devices]
            model = FinalCallModel(
                LeaseGuardModel(
                    ImageFallbackModel(CompactToolsModel(model)),
                    job.process_id,
                    granted,
                    job.world_devices,
                    recorded,
                )
            )
        agent = Agent(
            model,
            instructions=process_system_prompt(job.base_prompt, job_text(job), job.devices),
            toolsets=toolsets,
            name=f"process-{job.process_id}",
        )
        result = await agent.run(job_text(job), usage_limits=UsageLimits(request_limit=job.request_limit))
    except BaseException:
        await SESSIONS.forget(job.devices)
        raise
    return str(result.output)


async def _connect(device: GrantedDevice, images: int | None = None) -> MCPToolset[Any]:
    """Open the device's MCP session up front, so a dead device is reported by name, not as a stack."""
    headers = {**image_headers(images), **owner_headers()}
    transport = StreamableHttpTransport(
        device.url, headers=headers, auth=device.token, verify=shared_context()
    )
    client: Client[Any] = Client(
        transport,
        name=f"rosaos-{device.name}",
        init_timeout=CONNECT_TIMEOUT,
        progress_handler=PROGRESS.handler(device.name),
    )
    # 'failed': a device error (bulb offline, value refused) goes back to the model as a failed
    # tool result it can read and report, instead of ending the whole run.
    toolset: MCPToolset[Any] = ListedToolset(client, id=device.name, tool_error_behavior="failed")
    try:
        await toolset.__aenter__()
    except Exception as failure:
        refused = await _refused_token(device)
        if refused:
            raise DeviceUnreachable(
                f"device {device.name} at {device.url} refused the bearer token ({refused}); "
                "check the token configured for it"
            ) from failure
        raise DeviceUnreachable(
            f"cannot reach device {device.name} at {device.url}: {describe_error(failure)}; "
            "check that it is served and healthy (rosaos devices list)"
        ) from failure
    return toolset


async def _refused_token(device: GrantedDevice) -> str | None:
    """After a failed connect: whether the server answered 401/403 (the MCP error does not say)."""
    try:
        async with httpx.AsyncClient(timeout=CONNECT_TIMEOUT, verify=shared_context()) as http:
            response = await http.post(device.url, headers={"Authorization": f"Bearer {device.token}"})
    except httpx.HTTPError:
        return None
    return f"HTTP {response.status_code}" if response.status_code in (401, 403) else None


def describe_error(failure: BaseException) -> str:
    """A one-line, readable description of ``failure``: our own errors by message, others by type too."""
    while isinstance(failure, BaseExceptionGroup) and failure.exceptions:
        failure = failure.exceptions[0]
    if isinstance(failure, DeviceUnreachable | ModelError):
        return str(failure)
    text = str(failure).strip().splitlines()[0] if str(failure).strip() else ""
    return f"{type(failure).__name__}: {text}" if text else type(failure).__name__


def count_usage(messages: Sequence[ModelMessage]) -> tuple[int, int]:
    """Model requests (responses received) and tool calls made, from a run's messages."""
    responses = [message for message in messages if isinstance(message, ModelResponse)]
    asked = [
        response for response in responses if response.model_name != FINAL_CALL_MODEL
    ]  # not the local end
    return len(asked), sum(len(response.tool_calls) for response in responses)


class ProtocolWriter:
    """Writes protocol lines to the worker's real stdout; everything else printed goes to stderr."""

    def __init__(self) -> None:
        sys.stdout.flush()
        self._stream: IO[str] = os.fdopen(os.dup(1), "w", buffering=1, encoding="utf-8")
        os.dup2(2, 1)
        sys.stdout = sys.stderr

    def send(self, message: Ready | Progress | Done | Rejected) -> None:
        """Write one message line. A small write to a pipe the pool always drains; it does not block."""
        self._stream.write(encode(message))
        self._stream.flush()


async def _stdin_reader() -> asyncio.StreamReader:
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader(limit=LINE_LIMIT)
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    return reader


async def _run_while_owned(job: WorkerJob, reader: asyncio.StreamReader) -> WorkerCallback | None:
    """Run ``job``, unless stdin closes first: then the kernel died, and the job must not go on.

    The pool writes nothing while a job runs, so the only thing stdin can bring meanwhile is its
    end. A robot never moves without an owner: the job is cancelled (its MCP calls with it) and
    every granted device gets ``safe_stop`` before this worker exits. Returns None in that case.
    """
    running = asyncio.create_task(run_job(job), name=f"process-{job.process_id}")
    ended = asyncio.create_task(reader.read(), name="stdin-eof")  # read() returns at EOF
    await asyncio.wait({running, ended}, return_when=asyncio.FIRST_COMPLETED)
    if running.done():
        ended.cancel()
        # Wait until the read is really off the stream, or the next readline() finds it still there.
        with contextlib.suppress(asyncio.CancelledError):
            await ended
        return running.result()
    log.warning("process %d: the kernel is gone; stopping the job and its devices", job.process_id)
    running.cancel()
    with contextlib.suppress(BaseException):
        await running
    await safe_stop_devices(job.devices)
    return None


async def safe_stop_devices(devices: Sequence[GrantedDevice], timeout: float = ORPHAN_STOP_TIMEOUT) -> None:
    """Call every device's ``safe_stop`` at once, over fresh sessions; failures are logged, not raised."""

    async def stop(device: GrantedDevice) -> None:
        try:
            async with asyncio.timeout(timeout):
                client: Client[Any] = Client(device.url, auth=device.token, init_timeout=timeout)
                async with client:
                    await client.call_tool("safe_stop", {})
            log.warning("device %s: safe_stop done (the process that held it lost its kernel)", device.name)
        except Exception as failure:
            log.error("device %s: safe_stop failed: %s", device.name, describe_error(failure))

    await asyncio.gather(*(stop(device) for device in devices))


async def serve(protocol: ProtocolWriter) -> None:
    """Announce readiness, then run each job read from stdin until stdin closes."""
    reader = await _stdin_reader()
    protocol.send(Ready(pid=os.getpid()))
    PROGRESS.send = protocol.send
    while line := await reader.readline():
        if not line.strip():
            continue
        try:
            job = WorkerJob.model_validate_json(line)
        except ValidationError as invalid:
            log.error("rejected a job that is not a valid WorkerJob: %s", invalid)
            protocol.send(Rejected(error=f"not a valid WorkerJob: {invalid}"))
            continue
        log.info("process %d: starting %r with %d device(s)", job.process_id, job.task, len(job.devices))
        PROGRESS.process_id = job.process_id
        try:
            callback = await _run_while_owned(job, reader)
        finally:
            PROGRESS.process_id = None
        if callback is None:
            return  # the kernel is gone: nobody owns this process any more
        log.info("process %d: %s", job.process_id, callback.status)
        protocol.send(Done(process_id=job.process_id, callback=callback))


def main() -> None:
    """Entry point of ``python -m rosaos.processes.worker``."""
    # Libraries (httpx, mcp) log every request at INFO; only their warnings are worth a line.
    logging.basicConfig(
        level=logging.WARNING,
        stream=sys.stderr,
        format=f"worker[{os.getpid()}] %(levelname)s %(name)s: %(message)s",
    )
    logging.getLogger("rosaos").setLevel(os.environ.get("ROSAOS_WORKER_LOG", "INFO").upper())
    spans_off()  # FastMCP's per-request spans go nowhere here (rosaos/fastmcp_spans.py)
    protocol = ProtocolWriter()
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(serve(protocol))


if __name__ == "__main__":
    main()
