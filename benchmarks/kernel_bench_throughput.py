"""Throughput for ``kernel.py``: the event queue and the kernel loop under load, and single round trips.

A kernel with a no-op model (and no pool) first times single requests while idle, then takes
``--events`` chats from a separate load-generator process: ``kernel.py --load-generator URL COUNT
CLIENTS KIND``, reading the API token on stdin, so its clients do not share the kernel's event
loop. ``KIND`` is ``raw`` (HTTP/1.1 written on kept-open sockets: :func:`raw_load_generator`) or
``httpx`` (the clients used until issue 26, whose own CPU cost capped the rate on 2 cores). The store's own commit and handled time stamps give the enqueue and end-to-end rates.
"""

from __future__ import annotations

import asyncio
import json
import os
import sys
import time
from collections.abc import Awaitable, Callable, Coroutine
from typing import TYPE_CHECKING, Any

import httpx
from kernel_bench_harness import DEVICE, HERE, drained, now, running_kernel, summary
from kernel_bench_resources import memory

if TYPE_CHECKING:
    from rosaos.kernel.runtime import Kernel

ENTRY_POINT = HERE / "kernel.py"
"""The script the load generator runs as, with the hidden ``--load-generator`` flag."""


async def throughput(
    count: int, clients: int, round_trip_samples: int, load_client: str = "raw"
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Post ``count`` chats from ``clients`` clients in another process; time enqueue and handling.

    Also returns the single-request round trips, timed on the same (idle) kernel first.
    """
    import bench_models

    async with running_kernel(pool_size=0, kernel_model=bench_models.noop_model()) as (kernel, start_seconds):
        single = {"kernel_start_seconds": start_seconds, **await round_trips(kernel, round_trip_samples)}
        handle_ms: list[float] = []
        batch_sizes: list[int] = []
        handle_batch = kernel.loop.handle_batch

        # The loop takes what has queued up in one batch (one transaction, one model turn per
        # event); a sample is the batch's time divided by its events, once per event.
        async def timed_handle_batch(events: list[Any]) -> Any:
            started = now()
            try:
                return await handle_batch(events)
            finally:
                per_event = (now() - started) * 1000 / max(len(events), 1)
                handle_ms.extend([per_event] * len(events))
                batch_sizes.append(len(events))

        kernel.loop.handle_batch = timed_handle_batch  # type: ignore[method-assign]
        # Warm up the API, the store and the agent, then start from an empty queue.
        headers = {"Authorization": f"Bearer {kernel.token}"}
        async with httpx.AsyncClient(base_url=kernel.url, headers=headers, timeout=30) as api:
            for index in range(20):
                (await api.post("/chat", json={"text": f"warm-up {index}"})).raise_for_status()
        await drained(kernel)
        handle_ms.clear()
        batch_sizes.clear()
        cpu_before = time.process_time()
        process = await asyncio.create_subprocess_exec(
            sys.executable,
            str(ENTRY_POINT),
            "--load-generator",
            kernel.url,
            str(count),
            str(clients),
            load_client,
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
        )
        out, _ = await process.communicate(kernel.token.encode())
        if process.returncode != 0:
            raise RuntimeError(f"the load generator failed (exit code {process.returncode})")
        load = json.loads(out)
        await drained(kernel)
        # The kernel's whole process, every thread (the API, the loop, the SQLite thread), from
        # before the load generator starts to the queue drained: robust to the machine's load,
        # where the rates are not. It includes the idle kernel while the generator starts up.
        kernel_cpu = time.process_time() - cpu_before
        first, last = load["ids"]
        rows = await kernel.events.database.fetch(
            "SELECT count(*), min(time), max(time), min(handled_at), max(handled_at), "
            "sum(handled_at > ?) FROM events WHERE id BETWEEN ? AND ?",
            (load["last_ack"], first, last),
        )
        memory_kernel = memory(os.getpid())
    stored, first_commit, last_commit, first_handled, last_handled, after_enqueue = rows[0]
    tail = last_handled - load["last_ack"]
    return single, {
        "events": count,
        "clients": clients,
        "load_client": load_client,
        "stored": stored,
        "errors": load["errors"],
        "enqueue_seconds": load["last_ack"] - load["first_send"],
        "enqueue_per_second": count / (load["last_ack"] - load["first_send"]),
        "commit_per_second": (stored - 1) / (last_commit - first_commit)
        if last_commit > first_commit
        else None,
        "end_to_end_seconds": last_handled - load["first_send"],
        "end_to_end_per_second": count / (last_handled - load["first_send"]),
        "handled_per_second": (stored - 1) / (last_handled - first_handled),
        "handled_after_enqueue": after_enqueue,
        "drain_per_second": after_enqueue / tail if after_enqueue >= 20 and tail > 0 else None,
        "backlog_at_last_ack": after_enqueue,
        "post_ms": summary(load["latencies_ms"]),
        "kernel_handle_ms": summary(handle_ms),
        "kernel_batches": len(batch_sizes),
        "kernel_cpu_ms_per_event": kernel_cpu * 1000 / count,
        "kernel_process_memory": memory_kernel,
    }


async def load_generator(url: str, count: int, clients: int, token: str) -> dict[str, Any]:
    """Post ``count`` chats as fast as ``clients`` sequential clients can; wall-clock times."""
    remaining = iter(range(count))
    latencies: list[float] = []
    ids: list[int] = []
    errors = 0
    headers = {"Authorization": f"Bearer {token}"}
    start = asyncio.Event()

    async def client() -> None:
        nonlocal errors
        async with httpx.AsyncClient(base_url=url, headers=headers, timeout=30) as http:
            await http.get("/health")  # connect before the clock starts
            await start.wait()
            for index in remaining:
                sent = time.perf_counter()
                response = await http.post("/chat", json={"text": f"noop {index}"})
                latencies.append((time.perf_counter() - sent) * 1000)
                if response.status_code == 202:
                    ids.append(response.json()["id"])
                else:
                    errors += 1

    first_send, last_ack = await _race(clients, client, start)
    return {
        "first_send": first_send,
        "last_ack": last_ack,
        "latencies_ms": latencies,
        "ids": [min(ids), max(ids)],
        "errors": errors,
    }


async def raw_load_generator(url: str, count: int, clients: int, token: str) -> dict[str, Any]:
    """As :func:`load_generator`, but each client writes HTTP/1.1 on a kept-open socket itself.

    httpx spends about 1.2 ms of CPU per request (measured in this load generator, issue 26): on
    2 cores the generator then takes one core from the kernel it measures, and caps the rate near
    800/s whatever the kernel does. These clients send the same request (same headers and body,
    keep-alive) and read the whole answer, for about a tenth of that.
    """
    parsed = httpx.URL(url)
    remaining = iter(range(count))
    latencies: list[float] = []
    ids: list[int] = []
    errors = 0
    start = asyncio.Event()

    async def client() -> None:
        nonlocal errors
        reader, writer = await asyncio.open_connection(parsed.host, parsed.port)
        head = (
            f"POST /chat HTTP/1.1\r\nhost: {parsed.host}:{parsed.port}\r\nauthorization: Bearer {token}\r\n"
        )
        await start.wait()
        for index in remaining:
            body = json.dumps({"text": f"noop {index}"}).encode()
            sent = time.perf_counter()
            writer.write(
                f"{head}content-type: application/json\r\ncontent-length: {len(body)}\r\n\r\n".encode() + body
            )
            status_line, *headers = (await reader.readuntil(b"\r\n\r\n")).decode("latin-1").split("\r\n")
            length = next(int(h.split(":", 1)[1]) for h in headers if h.lower().startswith("content-length:"))
            answer = await reader.readexactly(length)
            latencies.append((time.perf_counter() - sent) * 1000)
            if status_line.split()[1] == "202":
                ids.append(json.loads(answer)["id"])
            else:
                errors += 1
        writer.close()

    first_send, last_ack = await _race(clients, client, start)
    return {
        "first_send": first_send,
        "last_ack": last_ack,
        "latencies_ms": latencies,
        "ids": [min(ids), max(ids)],
        "errors": errors,
    }


async def _race(
    clients: int, client: Callable[[], Coroutine[Any, Any, None]], start: asyncio.Event
) -> tuple[float, float]:
    """Run ``clients`` copies of ``client``; each connects, then waits for ``start``. The wall
    clock at the start and after the last answer."""
    tasks = [asyncio.create_task(client()) for _ in range(clients)]
    await asyncio.sleep(0.5)  # every client connected before the clock starts
    first_send = time.time()
    start.set()
    await asyncio.gather(*tasks)
    return first_send, time.time()


async def round_trips(kernel: Kernel, times: int) -> dict[str, Any]:
    """Single requests: kernel ``GET /health``, MCP session open, ``get_state`` on an open session."""
    from rosaos.devices.client import DeviceClient

    endpoint = kernel.endpoints()[DEVICE]
    assert endpoint.url is not None
    health, opens, calls = [], [], []
    async with httpx.AsyncClient(base_url=kernel.url, timeout=30) as api:
        await api.get("/health")
        for _ in range(times):
            health.append(await timed(lambda: api.get("/health")))
    for _ in range(times):
        client = DeviceClient(endpoint.url, endpoint.token, 10, DEVICE)
        started = now()
        async with client:
            opens.append((now() - started) * 1000)
    async with DeviceClient(endpoint.url, endpoint.token, 10, DEVICE) as client:
        await client.get_state()
        for _ in range(times):
            calls.append(await timed(client.get_state))
    return {
        "kernel_health_ms": summary(health),
        "mcp_session_open_ms": summary(opens),
        "mcp_get_state_ms": summary(calls),
    }


async def timed(call: Callable[[], Awaitable[Any]]) -> float:
    started = now()
    await call()
    return (now() - started) * 1000
