"""How a browser gets in: one-time login codes.

The web page gets the bearer token without it ever being in a URL.

``rosaos up`` prints ``http://127.0.0.1:8765/#login=<code>``. The browser never sends the part
after ``#`` to the server, so the code stays out of logs and referrers. The page posts the code
to ``/login`` and receives the token, which it keeps in ``sessionStorage``.

A code works once, expires after ten minutes, and is compared in constant time. Codes live in
memory only: a restart invalidates them, which is what you want for a secret printed to a
terminal. The CLI mints a fresh link through ``POST /login-codes`` (which needs the token).

:class:`rosaos.auth.HostOriginGuard` refuses browser requests sent from any other origin, so a web
page elsewhere cannot drive the robot through the user's browser (not even ``/login``).
"""

from __future__ import annotations

import hashlib
import hmac
import secrets
import time
from collections.abc import Callable
from dataclasses import dataclass

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
