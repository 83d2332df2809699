"""The caller's tool in a remote :class:`surfeledit.Session` (issue 11 §1): every client attached to a
session has its own tool -- its regions, deformation fields, collision detector and settings -- and a
lock on the surfels its tool can move (every surfel outside its zero region). ``set_regions`` that would
overlap another client's lock raises :class:`~surfeledit.errors.ConflictError` (field ``"regions"``,
naming that client and how many surfels overlap). The in-process twin is
:meth:`surfeledit.local.LocalSession.release`.
"""

from __future__ import annotations

from typing import Any

from ._protocol import proto


__all__ = ["ToolOps"]


class ToolOps:
    """Mixin of :class:`surfeledit.Session` (uses its ``_request``); watchers get the cause ``"release"``."""

    version: int

    def _request(self, op: "proto.Op", **args: Any) -> "proto.Reply":  # pragma: no cover - Session's
        raise NotImplementedError

    def release(self) -> bool:
        """Frees this client's tool: its regions, detector and lock (its settings stay). One history entry
        (``"release"``) and a new version; False, and nothing changes, when the tool has no regions.
        Closing the session (or being detached by a lease) releases it too."""
        before = self.version
        reply = self._request(proto.Op.OP_RELEASE)
        return int(reply.version) != before
