"""Presence result types (issue 11): :class:`Peer` (one client of a session, ``session.peers()``) and
:class:`PresenceEvent` (a join, leave, lease expiry or region change on the update stream,
``watcher.presence()``). Frozen dataclasses; times in milliseconds, sizes in surfels.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, List, Tuple

__all__ = ["Peer", "PresenceEvent", "peer_of", "presence_of", "PresenceCallback"]


@dataclasses.dataclass(frozen=True)
class Peer:
    """One client of a session.

    Attributes:
        client_id: the client's id. role: ``"owner"``, ``"editor"`` or ``"viewer"``.
        state: ``"attached"``; ``"lease"`` (its request writer is gone; it is detached when its lease
            runs out); ``"away"`` (detached by its lease; its membership is kept for the server's grace
            period, so that it can come back with the same client id).
        last_op: its last op that changed the session (``"deform"``, ``"set_regions"``, ...; ``""`` before any).
        last_version: the session version that op produced (0 before any).
        idle_ms: milliseconds since its last request to the session (away: since it was detached).
        zero, one, deformable: its tool: surfels of its zero region, of its one region, and that it
            may move (the one region and the band between, s > 0).
    """

    client_id: str
    role: str
    state: str
    last_op: str
    last_version: int
    idle_ms: float
    zero: int
    one: int
    deformable: int


@dataclasses.dataclass(frozen=True)
class PresenceEvent:
    """A presence change of a session (an update with cause ``"presence"``).

    Attributes:
        session: the session's name. version: the session version at the time (presence changes do not
            change it). client: the client it is about. what: ``"join"`` (attached), ``"leave"`` (closed the
            session), ``"expired"`` (detached by its lease: killed or cut off) or ``"regions"`` (its tool's
            regions changed). peers: every peer after the change (as ``session.peers()``).
    """

    session: str
    version: int
    client: str
    what: str
    peers: Tuple[Peer, ...]


#: A watcher's presence callback: called on the thread that drains the watcher (get / poll / presence).
PresenceCallback = Callable[[PresenceEvent], None]


def peer_of(wire: Any) -> Peer:
    """The :class:`Peer` of a wire ``proto.Peer``."""
    return Peer(client_id=str(wire.client_id), role=str(wire.role), state=str(wire.state), last_op=str(wire.last_op),
                last_version=int(wire.last_version), idle_ms=float(wire.idle_ms), zero=int(wire.zero),
                one=int(wire.one), deformable=int(wire.deformable))


def presence_of(update: Any) -> PresenceEvent:
    """The :class:`PresenceEvent` of a wire ``proto.Update`` with cause ``"presence"``."""
    peers: List[Peer] = [peer_of(p) for p in update.peers]
    return PresenceEvent(session=str(update.session), version=int(update.version), client=str(update.author),
                         what=str(update.presence), peers=tuple(peers))
