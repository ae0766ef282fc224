"""Fixtures for the kernel tests: a real event store in ``tmp_path``, the runtime, the API.

``client`` speaks to the app in-process (httpx ``ASGITransport``); ``served`` puts it on a
loopback port with uvicorn, for streaming and the browser.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
from collections.abc import AsyncIterator
from pathlib import Path

import httpx
import pytest
import uvicorn
from fastapi import FastAPI

from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.api.app import create_app
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.updates import UpdateStream
from rosaos.memory.sightings import SightingLog
from rosaos.memory.store import MemoryStore
from rosaos.timers.timer_book import TimerBook

from .kernel_support import ORIGIN, TestRuntime, eventually, kitchen_light
from .web_support import page  # noqa: F401  (the Chromium fixture of the web page tests)


@pytest.fixture
async def store(tmp_path: Path) -> AsyncIterator[EventStore]:
    opened = await EventStore.open(tmp_path / "kernel.sqlite3")
    yield opened
    await opened.close()


@pytest.fixture
async def updates(store: EventStore) -> UpdateStream:
    return await UpdateStream.open(store.database)


@pytest.fixture
async def runtime(store: EventStore, updates: UpdateStream, tmp_path: Path) -> TestRuntime:
    activity = await ActivityLog.open(store.database)
    timers = await TimerBook.open(store)
    memory = MemoryStore.open(tmp_path / "memory")
    return TestRuntime(
        events=store,
        updates=updates,
        device_list=[kitchen_light()],
        activity=activity,
        timers=timers,
        memory=memory,
        sightings=SightingLog(memory),
    )


@pytest.fixture
def images_dir(tmp_path: Path) -> Path:
    """Where the app looks for camera frames (``<device>-<time>.jpg``)."""
    return tmp_path / "images"


@pytest.fixture
def app(runtime: TestRuntime, images_dir: Path) -> FastAPI:
    return create_app(runtime, images_dir=images_dir)


@pytest.fixture
async def client(app: FastAPI) -> AsyncIterator[httpx.AsyncClient]:
    """In-process HTTP client. Its base URL is the page's own origin, as a browser would use."""
    async with httpx.AsyncClient(transport=httpx.ASGITransport(app=app), base_url=ORIGIN) as http:
        yield http


@pytest.fixture
async def served(app: FastAPI) -> AsyncIterator[str]:
    """The app on a free loopback port; yields its base URL (``http://127.0.0.1:PORT``)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.bind(("127.0.0.1", 0))
    config = uvicorn.Config(app, log_level="warning", lifespan="off", timeout_graceful_shutdown=1)
    server = uvicorn.Server(config)
    task = asyncio.create_task(server.serve(sockets=[sock]))
    await eventually(lambda: server.started or task.done())
    if task.done():
        task.result()
    try:
        yield f"http://127.0.0.1:{sock.getsockname()[1]}"
    finally:
        server.should_exit = True
        with contextlib.suppress(asyncio.CancelledError):
            await task
        sock.close()
