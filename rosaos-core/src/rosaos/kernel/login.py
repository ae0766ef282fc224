"""How a browser gets in: one-time login codes, and the same-origin rule.

The web page gets the bearer token without it ever being in a URL.

``rosaos up`` prints ``http://127.0.0.1:8765/#login=<code>``. The browser never sends the part
after ``#`` to the server, so the code stays out of logs and referrers. The page posts the code
to ``/login`` and receives the token, which it keeps in ``sessionStorage``.

A code works once, expires after ten minutes, and is compared in constant time. Codes live in
memory only: a restart invalidates them, which is what you want for a secret printed to a
terminal. The CLI mints a fresh link through ``POST /login-codes`` (which needs the token).

:class:`SameOriginMiddleware` refuses browser requests sent from any other origin, so a web page
elsewhere cannot drive the robot through the user's browser (not even ``/login``).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import secrets
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from starlette.types import ASGIApp, Receive, Scope, Send

CODE_LIFETIME = 600.0
"""Seconds a login code stays valid."""
MAX_LIVE_CODES = 32
"""Minting more than this many unused codes forgets the oldest ones."""


@dataclass
class _Code:
    digest: bytes
    expires_at: float


def login_url(base_url: str, code: str) -> str:
    """The link to print: ``http://127.0.0.1:8765/#login=<code>``."""
    return f"{base_url.rstrip('/')}/#login={code}"


class LoginCodes:
    """Mints and redeems single-use login codes. ``clock`` is injectable for tests."""

    def __init__(self, lifetime: float = CODE_LIFETIME, clock: Callable[[], float] = time.monotonic) -> None:
        self.lifetime = lifetime
        self._clock = clock
        self._codes: list[_Code] = []

    def mint(self) -> str:
        """A new code, valid for :attr:`lifetime` seconds and for one login."""
        code = secrets.token_urlsafe(24)
        self._forget_expired()
        # Only a hash is kept: a memory dump of the server does not yield a usable code.
        self._codes.append(_Code(_digest(code), self._clock() + self.lifetime))
        del self._codes[:-MAX_LIVE_CODES]
        return code

    def redeem(self, code: str) -> bool:
        """True, once, for a live code; False for an unknown, used or expired one."""
        self._forget_expired()
        presented = _digest(code)
        match: _Code | None = None
        # Compare against every live code without stopping early, so timing says nothing.
        for candidate in self._codes:
            if hmac.compare_digest(candidate.digest, presented):
                match = candidate
        if match is None:
            return False
        self._codes.remove(match)
        return True

    def _forget_expired(self) -> None:
        now = self._clock()
        self._codes = [code for code in self._codes if code.expires_at > now]


def _digest(code: str) -> bytes:
    return hashlib.sha256(code.encode("utf-8", "surrogatepass")).digest()


class SameOriginMiddleware:
    """ASGI middleware: 403 when a request's ``Origin`` is neither this server's own nor allowed.

    Same-origin means the ``Origin`` header equals ``scheme://Host`` of the request itself, so the
    rule holds on any port (``rosaos up --port``, port 0 in tests). Requests without ``Origin``
    (curl, the CLI, workers, page navigations) pass; they still need the token where one is due.
    ``Host`` can be forged by DNS rebinding, but such a page never has the token.
    """

    def __init__(self, app: ASGIApp, allowed_origins: Iterable[str] = ()) -> None:
        self.app = app
        self._allowed = frozenset(allowed_origins)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http":
            headers = dict(scope.get("headers", []))
            origin = headers.get(b"origin", b"").decode("latin-1")
            host = headers.get(b"host", b"").decode("latin-1")
            if origin and origin != f"{scope.get('scheme', 'http')}://{host}" and origin not in self._allowed:
                body = json.dumps({"detail": f"origin {origin} is not allowed: open the rosaOS page itself"})
                await send(
                    {
                        "type": "http.response.start",
                        "status": 403,
                        "headers": [(b"content-type", b"application/json")],
                    }
                )
                await send({"type": "http.response.body", "body": body.encode()})
                return
        await self.app(scope, receive, send)
