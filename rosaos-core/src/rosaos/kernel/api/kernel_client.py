"""An HTTP client for a running kernel: what ``rosaos chat``, ``ps`` and ``kill`` use."""

from __future__ import annotations

import json
from pathlib import Path
from types import TracebackType
from typing import Any

import httpx

from rosaos.auth import token_path
from rosaos.config import RosaosConfig
from rosaos.devices.run_files import pid_alive

KERNEL_FILE = "run/kernel.json"
"""Where a running kernel says where it is, so `rosaos chat/ps/kill` find it even on --port 0."""


def kernel_file(data_dir: Path) -> Path:
    return data_dir / KERNEL_FILE


def running_kernel_url(data_dir: Path) -> str | None:
    """The URL of the kernel running on ``data_dir``, if one is (its process is alive)."""
    try:
        info = json.loads(kernel_file(data_dir).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(info, dict) or not pid_alive(int(info.get("pid", 0))):
        return None
    url = info.get("url")
    return url if isinstance(url, str) else None


class KernelUnavailable(Exception):
    """The kernel cannot be reached or refused us; the message says how to fix it."""


class KernelClient:
    """Talks to the kernel API with the bearer token from the data directory."""

    def __init__(self, base_url: str, token: str, timeout: float = 10.0) -> None:
        self.base_url = base_url.rstrip("/")
        self._http = httpx.AsyncClient(
            base_url=self.base_url,
            headers={"Authorization": f"Bearer {token}"},
            timeout=httpx.Timeout(timeout),
        )

    @classmethod
    def from_config(cls, config: RosaosConfig, url: str | None = None) -> KernelClient:
        """Client for ``url``, else the kernel running on this data directory, else ``[kernel] host/port``."""
        path = token_path(config.data_dir)
        if not path.is_file():
            raise KernelUnavailable(
                f"no token at {path}: start the kernel with `rosaos up` (it creates the token on first run)"
            )
        base = (
            url
            or running_kernel_url(config.data_dir)
            or f"http://{_host_for_client(config.kernel.host)}:{config.kernel.port}"
        )
        return cls(base, path.read_text(encoding="utf-8").strip())

    async def __aenter__(self) -> KernelClient:
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self._http.aclose()

    async def request(self, method: str, path: str, **kwargs: Any) -> Any:
        """One API call; raises :class:`KernelUnavailable` with the API's own explanation on failure."""
        try:
            response = await self._http.request(method, path, **kwargs)
        except httpx.ConnectError:
            raise KernelUnavailable(
                f"cannot reach the rosaOS kernel at {self.base_url}: is `rosaos up` running?"
            ) from None
        except httpx.TimeoutException:
            raise KernelUnavailable(f"the kernel at {self.base_url} did not answer in time") from None
        if response.status_code >= 400:
            try:
                detail = response.json().get("detail", response.text)
            except ValueError:
                detail = response.text
            if response.status_code == 401:
                detail = f"{detail} (is this the kernel of the same data directory?)"
            raise KernelUnavailable(f"{method} {path} failed with {response.status_code}: {detail}")
        return response.json() if response.content else None

    async def chat(self, text: str, idempotency_key: str | None = None) -> int:
        """Send typed text; returns the event id."""
        body: dict[str, Any] = {"text": text}
        if idempotency_key:
            body["idempotency_key"] = idempotency_key
        accepted = await self.request("POST", "/chat", json=body)
        return int(accepted["id"])

    async def event(self, event_id: int) -> dict[str, Any]:
        result: dict[str, Any] = await self.request("GET", f"/events/{event_id}")
        return result

    async def processes(self, include_ended: bool = False) -> list[dict[str, Any]]:
        params = {"all": "true"} if include_ended else {}
        result: list[dict[str, Any]] = await self.request("GET", "/processes", params=params)
        return result

    async def terminate(self, process_id: int) -> dict[str, Any]:
        result: dict[str, Any] = await self.request("POST", f"/processes/{process_id}/terminate")
        return result

    async def emergency_stop(self, reason: str) -> dict[str, Any]:
        result: dict[str, Any] = await self.request("POST", "/estop", json={"reason": reason})
        return result

    async def reset_emergency_stop(self) -> dict[str, Any]:
        result: dict[str, Any] = await self.request("POST", "/estop/reset")
        return result

    async def health(self) -> dict[str, Any]:
        result: dict[str, Any] = await self.request("GET", "/health")
        return result

    async def last_update_id(self) -> int:
        page = await self.request("GET", "/updates", params={"limit": 1})
        return int(page["last_id"])

    async def updates_after(self, after: int, limit: int = 200) -> tuple[list[dict[str, Any]], int]:
        """One page of updates after ``after``, and the cursor for the next call."""
        page = await self.request("GET", "/updates", params={"after": after, "limit": limit})
        return list(page["updates"]), int(page["last_id"])


def _host_for_client(host: str) -> str:
    """A wildcard bind address is reached on loopback."""
    if host in ("0.0.0.0", ""):
        return "127.0.0.1"
    if host == "::":
        return "[::1]"
    return f"[{host}]" if ":" in host else host
