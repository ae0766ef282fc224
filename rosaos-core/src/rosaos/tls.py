"""One TLS context per process, shared by the HTTP clients on the hot paths.

httpx (and the MCP client's httpx2) build a new default SSL context for every client, and
building one loads the whole CA bundle: 30 ms of CPU on a quiet machine, over 100 ms on a busy
one. A worker opened four clients per job (its device session, the lease keepalive twice, the
callback), so a burst of a hundred lamp commands spent more CPU loading certificates than
switching lamps, for connections that are plain HTTP on loopback. The context built here is the
one httpx would build (certifi's bundle, or ``SSL_CERT_FILE`` / ``SSL_CERT_DIR``), so an HTTPS
device is verified exactly as before; it is built once, and the fork server builds it before
forking, so every worker has it for free.
"""

from __future__ import annotations

import ssl
from functools import cache

import httpx


@cache
def shared_context() -> ssl.SSLContext:
    """The process's verifying TLS context; pass it as ``verify=`` to an HTTP client."""
    return httpx.create_ssl_context()
