"""The shared TLS context is built once per process and still verifies like httpx's default."""

from __future__ import annotations

import ssl

from rosaos.tls import shared_context


def test_one_context_per_process_that_verifies_certificates_and_host_names() -> None:
    context = shared_context()
    assert shared_context() is context
    assert context.verify_mode == ssl.CERT_REQUIRED
    assert context.check_hostname
    assert context.get_ca_certs()  # the CA bundle is loaded: HTTPS devices are verified
