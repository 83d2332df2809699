"""Presence operations of the remote :class:`surfeledit.Session` (issue 11): who else is in the session
(:meth:`PresenceOps.peers`). Presence changes arrive on the update stream (:meth:`surfeledit.Watcher.presence`).
"""

from __future__ import annotations

from typing import Any, List, Optional

from . import errors
from ._protocol import proto
from .presence import Peer, peer_of

__all__ = ["PresenceOps"]


class PresenceOps:
    """Mixin of :class:`surfeledit.Session` (uses its ``_request`` and ``client``)."""

    client: Any

    def _request(self, op: "proto.Op", expect_version: Optional[int] = None,
                 **args: Any) -> "proto.Reply":  # pragma: no cover - Session's
        raise NotImplementedError

    def peers(self) -> List[Peer]:
        """The session's clients, ordered by client id: every attached client (state ``"attached"``, or
        ``"lease"`` while its lease runs) and every client detached by its lease within the server's grace
        period (``"away"``), each with its role, last op and its version, idle time and tool sizes
        (:class:`~surfeledit.presence.Peer`). Any member may ask (viewers too)."""
        reply = self._request(proto.Op.OP_PEERS)
        peers = [peer_of(p) for p in reply.peers]
        ids = [p.client_id for p in peers]
        if ids != sorted(set(ids)):
            raise errors.InternalServerError(f"PEERS reply lists clients out of order or twice: {ids}", "peers")
        return peers

    def me(self) -> Optional[Peer]:
        """This client's own entry of :meth:`peers` (None when the server does not list it)."""
        mine = [p for p in self.peers() if p.client_id == self.client.client_id]
        return mine[0] if mine else None
