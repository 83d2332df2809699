"""connect(): spawning and stopping a local server, no-server errors, request timeouts with one retry."""

from __future__ import annotations

import logging
import time

import pytest

import surfeledit
from surfeledit import errors, proto

from .conftest import free_domain, server_executable


def test_spawn_true_starts_and_stops_a_server(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SURFELEDIT_SERVER", server_executable())
    domain = free_domain()
    monkeypatch.setenv("SURFELEDIT_DOMAIN", str(domain))
    with surfeledit.connect(spawn=True, timeout=10.0) as client:  # domain from the environment
        assert client.domain == domain
        proc = client._server
        assert proc is not None and proc.poll() is None
        assert client.info().max_chunk_surfels > 0
    assert proc.poll() is not None, "the spawned server was not stopped on close"


def test_spawn_false_without_server_raises() -> None:
    t0 = time.monotonic()
    with pytest.raises(errors.ServerStartError):
        surfeledit.connect(domain=free_domain(), spawn=False, timeout=1.0)
    assert time.monotonic() - t0 < 10.0


def test_timeout_retries_once_with_the_same_id(caplog: pytest.LogCaptureFixture) -> None:
    with surfeledit.Client(free_domain(), timeout=0.2) as client, caplog.at_level(logging.WARNING, "surfeledit"):
        req = client.new_request(proto.Op.OP_INFO)
        t0 = time.monotonic()
        with pytest.raises(errors.RequestTimeoutError) as info:
            client.call(req)
        elapsed = time.monotonic() - t0
        assert 0.35 < elapsed < 2.0
        assert "tried 2 times" in str(info.value)
        assert sum(f"no reply to request {req.request_id} " in r.getMessage() for r in caplog.records) == 2
        assert client.new_request(proto.Op.OP_INFO).request_id == req.request_id + 1  # retries reuse no id
