"""Leases and memory bounds against a real server: a client killed with SIGKILL mid-upload is
detached and its upload memory freed; uploads reserve memory as chunks arrive, within per-client
and total limits; a killed server is noticed within about two seconds (ServerGoneError)."""

from __future__ import annotations

import os
import signal
import threading
import time
from typing import Callable, List

import numpy as np
import pytest

import surfeledit
from surfeledit import errors
from surfeledit._protocol import proto

from .conftest import ServerProcess, connect_to, uploading_peer

ROW_BYTES = 7 * 8  # one surfel with a radius: positions, normals, radius as doubles
LEASE_MS = 1000
CLIENT_LIVELINESS_S = surfeledit._protocol.CLIENT_LIVELINESS_S


def chunk(offset: int, n: int) -> "proto.LoadChunk":
    rng = np.random.default_rng(offset)
    pos = rng.standard_normal((n, 3))
    return proto.LoadChunk(offset=offset, positions=pos.ravel().tolist(), normals=pos.ravel().tolist(),
                           radii=[0.01] * n)


def server_info(client: surfeledit.Client) -> "proto.ServerInfo":
    return client.info()


def test_a_client_killed_mid_upload_is_detached_and_its_upload_freed(
        start_server: Callable[..., ServerProcess]) -> None:
    srv = start_server("--client-lease-ms", str(LEASE_MS))
    owner = connect_to(srv)
    try:
        s = owner.open_session("shared")
        token = s.invite("editor")
        n, chunks = 5000, 2
        with uploading_peer(srv.domain, session="shared", token=token, total=100_000, chunks=chunks,
                            chunk=n) as peer:
            info = server_info(owner)
            # Reserved as chunks arrived (capacity doubles up to the total): 2 chunks of n -> 2n rows,
            # not the 100,000 rows LOAD_BEGIN announced.
            assert info.upload_bytes == chunks * n * ROW_BYTES
            assert info.client_upload_bytes == 0 and info.clients >= 2
            assert s.info().clients == 2
            peer.send_signal(signal.SIGKILL)
            killed = time.monotonic()
        deadline = killed + CLIENT_LIVELINESS_S + LEASE_MS / 1000 + 3.0
        while time.monotonic() < deadline:
            info = server_info(owner)
            if info.upload_bytes == 0 and s.info().clients == 1:
                break
            time.sleep(0.1)
        detached_after = time.monotonic() - killed
        assert info.upload_bytes == 0 and s.info().clients == 1, f"not detached {detached_after:.1f} s after SIGKILL"
        assert info.clients == 1
        assert "detached" in srv.log_tail(20000)
        # The owner goes on undisturbed.
        assert s.info().surfels == 0
    finally:
        owner.close()


def test_uploads_stay_within_per_client_and_total_memory_limits(
        start_server: Callable[..., ServerProcess]) -> None:
    srv = start_server("--max-client-upload-mb", "1", "--max-upload-mb", "2")
    a, b, c = connect_to(srv), connect_to(srv), connect_to(srv)
    try:
        info = server_info(a)
        assert info.max_client_upload_bytes == 1 << 20 and info.max_upload_bytes == 2 << 20
        sessions = {cl: cl.open_session(f"up-{i}") for i, cl in enumerate((a, b, c))}

        def send(cl: surfeledit.Client, offset: int, n: int) -> None:
            cl.request(proto.Op.OP_LOAD_CHUNK, sessions[cl].name, load_chunk=chunk(offset, n))

        for cl in (a, b, c):
            cl.request(proto.Op.OP_LOAD_BEGIN, sessions[cl].name,
                       load_begin=proto.LoadBegin(total=1_000_000, has_radii=True))
        assert server_info(a).upload_bytes == 0  # LOAD_BEGIN reserves nothing
        send(a, 0, 8000)
        send(a, 8000, 8000)  # 16,000 rows = 896,000 bytes
        held = server_info(a).client_upload_bytes
        assert held == 16000 * ROW_BYTES
        # 24,000 rows would be 1,344,000 bytes > 1 MiB: refused, nothing stored.
        with pytest.raises(errors.TooLargeError) as exc:
            send(a, 16000, 8000)
        assert exc.value.field == "load_chunk" and "per-client" in exc.value.message
        assert server_info(a).client_upload_bytes == held
        send(b, 0, 8000)
        send(b, 8000, 8000)
        # c is within its own limit, but all uploads would pass 2 MiB.
        with pytest.raises(errors.TooLargeError) as exc:
            send(c, 0, 8000)
        assert "server-wide" in exc.value.message
        assert server_info(c).upload_bytes == 2 * held
        # Closing a's session frees its upload; c fits now.
        sessions[a].close()
        assert server_info(c).upload_bytes == held
        send(c, 0, 8000)
        assert server_info(c).client_upload_bytes == 8000 * ROW_BYTES
    finally:
        for cl in (a, b, c):
            cl.close()


def test_a_killed_server_raises_server_gone_within_two_seconds(
        start_server: Callable[..., ServerProcess]) -> None:
    srv = start_server()
    client = connect_to(srv)
    try:
        client.info()
        os.kill(srv.proc.pid, signal.SIGKILL)
        srv.proc.wait()
        killed = time.monotonic()
        with pytest.raises(errors.ServerGoneError):
            client.info()
        assert time.monotonic() - killed < 2.5
    finally:
        client.close()


def test_a_request_in_flight_raises_server_gone_when_the_server_dies(
        start_server: Callable[..., ServerProcess]) -> None:
    srv = start_server()
    client = connect_to(srv)
    outcome: List[BaseException] = []

    def wait_for_reply() -> None:
        # The server is stopped, then killed while the request waits for its reply.
        os.kill(srv.proc.pid, signal.SIGSTOP)
        try:
            client.request(proto.Op.OP_INFO)
        except BaseException as e:  # noqa: BLE001 - recorded for the assertion
            outcome.append(e)

    try:
        client.info()
        t = threading.Thread(target=wait_for_reply)
        t.start()
        time.sleep(0.3)
        os.kill(srv.proc.pid, signal.SIGKILL)
        killed = time.monotonic()
        t.join(timeout=10)
        assert not t.is_alive()
        assert outcome and isinstance(outcome[0], errors.ServerGoneError), outcome
        assert time.monotonic() - killed < 2.5
    finally:
        client.close()
