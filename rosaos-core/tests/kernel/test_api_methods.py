"""A 405 names every method its path serves, and a login body that is not UTF-8 gets a listed answer."""

from __future__ import annotations

import httpx
import pytest
from fastapi import FastAPI

from .kernel_support import TestRuntime


@pytest.mark.parametrize(
    ("path", "methods"),
    [
        ("/estop", {"GET", "POST"}),
        ("/confirmations", {"GET"}),
        ("/confirmations/1", {"POST"}),
    ],
)
async def test_a_405_lists_every_method_of_its_path(
    client: httpx.AsyncClient, runtime: TestRuntime, path: str, methods: set[str]
) -> None:
    answer = await client.options(path, headers={"Authorization": f"Bearer {runtime.token}"})
    assert answer.status_code == 405
    allowed = {method.strip() for method in answer.headers["allow"].split(",")}
    assert methods <= allowed, answer.headers["allow"]


async def test_a_login_body_that_is_not_utf8_gets_an_answer_its_schema_lists(
    client: httpx.AsyncClient, app: FastAPI
) -> None:
    answer = await client.post("/login", content=b'{"code": "' + b"\xff\xfe" + b'"}')
    listed = app.openapi()["paths"]["/login"]["post"]["responses"]
    assert str(answer.status_code) in listed, (answer.status_code, sorted(listed))
    assert answer.json()["detail"]
