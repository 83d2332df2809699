"""Requests that survive a server restart (``Client(..., reconnect=seconds)``, PROTOCOL.md "Journal").

A server started with ``--journal DIR`` recovers its sessions after a crash and remembers the
replies of the request ids it served. When a request's server is gone (:class:`ServerGoneError`),
a client with ``reconnect > 0`` re-sends the *same* request (same client id and request id) until
a server answers or ``reconnect`` seconds passed: a request the crashed server had made durable is
answered from the recovered reply cache, one it had not is applied now; never both.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Any

from . import errors

if TYPE_CHECKING:  # pragma: no cover
    from .connection import Client

__all__ = ["await_reply_across_restart"]

_log = logging.getLogger("surfeledit")

_RESEND_S = 0.25  # how often the request is re-sent while no server answers (discovery takes milliseconds)


def await_reply_across_restart(client: "Client", request: Any, reconnect_s: float) -> Any:
    """Re-sends ``request`` every _RESEND_S seconds until its reply arrives; raises ServerGoneError
    when none came within ``reconnect_s`` seconds (the caller holds the client's request lock)."""
    deadline = time.monotonic() + reconnect_s
    _log.warning("server gone while request %d waited; re-sending it for up to %.1f s", request.request_id,
                 reconnect_s)
    while True:
        client._server_seen = False  # the new server's reply writer appears with its first reply
        client._writer.write(request)
        try:
            reply = client._wait_reply(request.request_id, min(deadline, time.monotonic() + _RESEND_S))
        except errors.ServerGoneError:
            reply = None  # the restarted server is gone again: keep trying until the deadline
        if reply is not None:
            return reply
        if time.monotonic() >= deadline:
            raise errors.ServerGoneError(
                f"no surfeledit server on domain {client.domain} answered request {request.request_id} "
                f"within {reconnect_s:.1f} s after the server was gone")
