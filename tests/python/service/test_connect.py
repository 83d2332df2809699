"""connect(): spawning and stopping a local server, no-server errors, request timeouts with one retry."""

from __future__ import annotations

import logging
import threading
import time
from typing import List

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


def test_two_clients_spawning_at_once_share_one_server(monkeypatch: pytest.MonkeyPatch) -> None:
    """Both find no server and spawn one at the same moment: the later server gives way (PROTOCOL.md "One
    server per domain") and its client uses the earlier one, so one server runs and both clients are served."""
    monkeypatch.setenv("SURFELEDIT_SERVER", server_executable())
    domain = free_domain()
    clients: List[surfeledit.Client] = []
    failures: List[BaseException] = []
    start = threading.Barrier(2)

    def spawn() -> None:
        try:
            start.wait()
            clients.append(surfeledit.connect(domain=domain, spawn=True, timeout=20.0))
        except BaseException as e:  # reported below
            failures.append(e)

    threads = [threading.Thread(target=spawn) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60.0)
    try:
        assert not failures, failures
        assert len(clients) == 2
        owners = [c for c in clients if c._server is not None]
        assert len(owners) == 1, "both clients kept a server of their own on one domain"
        for c in clients:
            assert c.info().max_chunk_surfels > 0
    finally:
        for c in sorted(clients, key=lambda c: c._server is not None):  # the owner last: it stops the server
            c.close()


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
