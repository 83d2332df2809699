"""Detaching a client killed with SIGKILL does not stall the others (PROTOCOL.md "Leases"): the
dead client's reply writer still has a matched reader (the dead process's, until discovery's own
lease runs out) that never acknowledges, and Cyclone's dds_delete of such a writer lingers for up to
its WriterLingerDuration (1 s). The server deletes it off the request thread, so a client that keeps
asking while the dead one is detached gets every answer promptly."""

from __future__ import annotations

import signal
import time
from typing import Callable, List

import surfeledit

from .conftest import ServerProcess, connect_to, uploading_peer

LEASE_MS = 1000
CLIENT_LIVELINESS_S = surfeledit._protocol.CLIENT_LIVELINESS_S
STALL_S = 0.6  # well below the 1 s linger, well above a round trip on a loaded 2-core machine


def test_detaching_a_killed_client_does_not_stall_the_others(start_server: Callable[..., ServerProcess]) -> None:
    srv = start_server("--client-lease-ms", str(LEASE_MS))
    owner = connect_to(srv)
    try:
        s = owner.open_session("shared")
        token = s.invite("editor")
        # A peer in its own process joins and gets replies (the server makes its reply writer).
        with uploading_peer(srv.domain, session="shared", token=token, total=1000, chunks=3, chunk=10) as peer:
            assert s.info().clients == 2
            peer.send_signal(signal.SIGKILL)
            killed = time.monotonic()
        # The owner asks back to back through the detachment and a while after it.
        rtts: List[float] = []
        detached_at = None
        deadline = killed + CLIENT_LIVELINESS_S + LEASE_MS / 1000 + 5.0
        while time.monotonic() < deadline:
            t0 = time.perf_counter()
            clients = s.info().clients
            rtts.append(time.perf_counter() - t0)
            if clients == 1 and detached_at is None:
                detached_at = time.monotonic()
            if detached_at is not None and time.monotonic() > detached_at + 2.0:
                break
        assert detached_at is not None, f"the killed peer was not detached:\n{srv.log_tail()}"
        assert "detached" in srv.log_tail(20000)
        worst = max(rtts)
        print(f"worst round trip {worst * 1e3:.0f} ms over {len(rtts)} requests (median "
              f"{sorted(rtts)[len(rtts) // 2] * 1e3:.2f} ms) while the killed peer was detached")
        assert worst < STALL_S, (f"a request waited {worst * 1e3:.0f} ms while the killed peer was detached "
                                 f"({len(rtts)} requests)")
    finally:
        owner.close()
