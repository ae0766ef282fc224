"""The bearer token that guards every rosaOS HTTP surface (device servers and the kernel API).

The token is generated on first use and stored in ``<data_dir>/token`` with mode 0600. Local
clients (the CLI, workers, device hosts) read it from there; a remote instance is given its own.
"""

from __future__ import annotations

import hmac
import ipaddress
import json
import os
import secrets
from collections.abc import Iterable
from pathlib import Path

from starlette.types import ASGIApp, Receive, Scope, Send

TOKEN_FILENAME = "token"


def token_path(data_dir: Path) -> Path:
    return data_dir / TOKEN_FILENAME


def private_dir(path: Path) -> Path:
    """Create ``path`` owner-only (0700), and narrow it to that if it is ours and wider.

    The data directory holds the token, the event store (the chat history) and the logs: other
    users of the machine must not read them.
    """
    path.mkdir(mode=0o700, parents=True, exist_ok=True)
    info = path.stat()
    if info.st_uid == os.getuid() and info.st_mode & 0o077:
        path.chmod(0o700)
    return path


def load_or_create_token(data_dir: Path) -> str:
    """Return the machine's token, creating it (0600, owner only) on first use.

    Also keeps the data directory owner-only (:func:`private_dir`): every command passes here.
    """
    private_dir(data_dir)
    path = token_path(data_dir)
    if path.exists():
        token = path.read_text(encoding="utf-8").strip()
        if token:
            return token
    token = secrets.token_urlsafe(32)
    # O_EXCL makes two first runs agree on one token instead of overwriting each other.
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        return path.read_text(encoding="utf-8").strip()
    with os.fdopen(fd, "w", encoding="utf-8") as handle:
        handle.write(token + "\n")
    return token


class BearerAuthMiddleware:
    """ASGI middleware: 401 unless ``Authorization: Bearer <token>``; 403 for foreign origins.

    ``open_paths`` are served without a token (``/health``). A browser request whose ``Origin``
    is not one of ``allowed_origins`` is refused, so a web page elsewhere cannot drive the robot
    through the user's browser.
    """

    def __init__(
        self,
        app: ASGIApp,
        token: str,
        open_paths: Iterable[str] = (),
        allowed_origins: Iterable[str] = (),
        token_query_paths: Iterable[str] = (),
    ) -> None:
        self.app = app
        self._token = token.encode()
        self._open = frozenset(open_paths)
        self._origins = frozenset(allowed_origins)
        self._query_paths = frozenset(token_query_paths)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            # Lifespan passes through; no rosaOS surface serves websockets, so refuse them.
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 4403})
                return
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        origin = headers.get("origin")
        if origin and self._origins and origin not in self._origins:
            await _json_error(send, 403, f"origin {origin} is not allowed")
            return
        path = scope.get("path", "")
        if path in self._open:
            await self.app(scope, receive, send)
            return
        presented = _bearer(headers.get("authorization", ""))
        if presented is None and path in self._query_paths:
            presented = _query_token(scope)
        if presented is None or not hmac.compare_digest(presented.encode(), self._token):
            reason = "missing bearer token" if presented is None else "wrong bearer token"
            await _json_error(
                send,
                401,
                f"{reason}: send 'Authorization: Bearer <token>' with the token from the rosaOS data directory",
                extra_headers=[(b"www-authenticate", b'Bearer realm="rosaos"')],
            )
            return
        await self.app(scope, receive, send)


def _bearer(value: str) -> str | None:
    scheme, _, credentials = value.partition(" ")
    if scheme.lower() != "bearer" or not credentials.strip():
        return None
    return credentials.strip()


def _query_token(scope: Scope) -> str | None:
    from urllib.parse import parse_qs

    query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
    values = query.get("token")
    return values[0] if values else None


async def _json_error(
    send: Send, status: int, detail: str, extra_headers: list[tuple[bytes, bytes]] | None = None
) -> None:
    body = json.dumps({"detail": detail}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    await send({"type": "http.response.start", "status": status, "headers": headers + (extra_headers or [])})
    await send({"type": "http.response.body", "body": body})


LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})


def host_name(host_header: str) -> str:
    """The name in a ``Host`` header, without its port: ``[::1]:8765`` → ``::1``."""
    host = host_header.strip().lower()
    if host.startswith("["):
        return host[1 : host.find("]")] if "]" in host else host
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


def is_loopback_name(name: str) -> bool:
    """``localhost``, ``::1`` or any 127.x.y.z."""
    if name in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def bound_hosts(bind_host: str) -> list[str]:
    """The names a server bound to ``bind_host`` answers to besides loopback (a specific address)."""
    if bind_host in ("", "0.0.0.0", "::") or is_loopback_name(bind_host):
        return []
    return [bind_host]


class HostOriginGuard:
    """ASGI middleware against DNS rebinding and foreign pages, on every rosaOS HTTP surface.

    As the MCP transport guidance asks: the ``Host`` header must name loopback or one of
    ``allowed_hosts`` (a rebinding attack sends the attacker's name), else 421; a browser's
    ``Origin``, when present, must be this same host (``scheme://Host``) or one of
    ``allowed_origins``, else 403. Requests without ``Origin`` (curl, the CLI, workers) pass.
    """

    def __init__(
        self, app: ASGIApp, allowed_hosts: Iterable[str] = (), allowed_origins: Iterable[str] = ()
    ) -> None:
        self.app = app
        self._hosts = frozenset(host_name(host) for host in allowed_hosts)
        self._origins = frozenset(allowed_origins)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":  # lifespan; websockets are refused by BearerAuthMiddleware
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        host = headers.get("host", "")
        name = host_name(host)
        if host and not is_loopback_name(name) and name not in self._hosts:
            await _json_error(
                send,
                421,
                f"host {host!r} is not served here (only loopback and allowed hosts are, against DNS "
                "rebinding); to reach it by that name, allow it: `rosaos serve-device --allow-host NAME` "
                "or [kernel] allow_hosts in rosaos.toml",
            )
            return
        origin = headers.get("origin")
        if origin and origin != f"{scope.get('scheme', 'http')}://{host}" and origin not in self._origins:
            await _json_error(send, 403, f"origin {origin} is not allowed: open the rosaOS page itself")
            return
        await self.app(scope, receive, send)
