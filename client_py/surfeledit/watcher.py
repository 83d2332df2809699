"""Watching a session's changes: :class:`Watcher` receives ``Update`` samples and reassembles their parts."""

from __future__ import annotations

import logging
import threading
import time
from typing import TYPE_CHECKING, Any, Dict, Iterator, List, Optional

import numpy as np

from . import errors
from ._protocol import proto
from .arrays import concat, join_clips, join_surfels
from .presence import PresenceCallback, PresenceEvent, presence_of
from .results import UpdateEvent

if TYPE_CHECKING:
    from .connection import Client

__all__ = ["Watcher", "ENCODINGS"]

#: The update encodings a watcher can choose (PROTOCOL.md "Updates" and "Updates, compact").
ENCODINGS = ("full", "compact")

_log = logging.getLogger("surfeledit")
_TAKE = 64  # samples taken from the reader at a time


class Watcher:
    """Receives a session's ``Update`` samples and reassembles multi-part changes.

    Use :meth:`get` (blocking with timeout), :meth:`poll` (non-blocking, e.g. from a GUI timer) or
    iterate (``for ev in watcher`` blocks; it ends after a ``close`` update or :meth:`close`).
    Updates are volatile: only changes made after the watcher was created arrive.

    Presence changes (updates with cause ``"presence"``: joins, leaves, lease expiries, region changes)
    are kept apart from the model's updates, so that applying what :meth:`get` returns reconstructs the
    model exactly: :meth:`presence` returns them, and ``on_presence`` (if given) is called with each as
    it is received (on the thread that drains: get, poll or presence).

    ``encoding``: ``"full"`` (default; doubles, exact) or ``"compact"`` (float32 positions relative to each
    part's box centre, octahedral 16-bit normals, float32 radii: about 28 instead of 64 bytes per surfel;
    error bounds in :mod:`surfeledit.compact`). The server encodes each only while a watcher reads it.
    """

    def __init__(self, client: "Client", session: str, on_presence: Optional[PresenceCallback] = None,
                 encoding: str = "full") -> None:
        if encoding not in ENCODINGS:
            raise errors.InvalidArgumentError(f"unknown update encoding {encoding!r} (one of {', '.join(ENCODINGS)})",
                                              field="encoding")
        self.client = client
        self.session = session
        self.encoding = encoding
        self._inbox = client.update_inbox(compact=encoding == "compact")
        if not self._inbox.greeted:
            _log.warning("watcher of %r: the server did not greet it in time (updates may be missed)", session)
        self._pending: Dict[int, Dict[int, "proto.Update"]] = {}
        self._ready: List[UpdateEvent] = []
        self._presence: List[PresenceEvent] = []
        self._on_presence = on_presence
        self._closed = False
        self._lock = threading.Lock()
        client.attach(self)

    @property
    def greeted(self) -> bool:
        """True once the server greeted this watcher's reader: every later update reaches it."""
        return self._inbox.greeted

    def wait_greeted(self, timeout: float) -> bool:
        """Waits up to ``timeout`` seconds more for the server's greeting when :meth:`Session.watch` gave
        up waiting (discovery on a loaded machine can take longer); True once greeted."""
        with self._lock:
            return self._inbox.greeted or self._inbox.await_greeting(timeout)

    def __enter__(self) -> "Watcher":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def close(self) -> None:
        """Stops receiving (idempotent); :meth:`get` and iteration then end."""
        if self._closed:
            return
        self._closed = True
        self.client.detach(self)
        self._inbox.close()

    def _drain(self) -> None:
        while True:
            samples = self._inbox.take(_TAKE)
            if not samples:
                return
            for s in samples:
                if isinstance(s, proto.Update) and s.session == self.session:
                    self._add(s)

    def _add(self, s: "proto.Update") -> None:
        """Keeps one part; when all ``parts`` of its version are in, queues their :class:`UpdateEvent`."""
        if s.cause == "presence":  # one sample, at the session's current version: not a model change
            event = presence_of(s)
            self._presence.append(event)
            if self._on_presence is not None:
                self._on_presence(event)
            return
        parts = max(1, int(s.parts))
        got = self._pending.setdefault(int(s.version), {})
        got[int(s.part)] = s
        if len(got) < parts:
            return
        del self._pending[int(s.version)]
        ordered = [got[i] for i in sorted(got)]
        first = ordered[0]
        ids, positions, normals, radii = join_surfels(ordered)
        self._ready.append(UpdateEvent(
            session=first.session, version=int(first.version), cause=first.cause, full=bool(first.full),
            step=int(first.step), author=str(first.author), ids=ids, positions=positions, normals=normals, radii=radii,
            removed=concat(ordered, "removed", np.uint64), detected=bool(first.detected),
            colliding=np.asarray(first.colliding, dtype=np.uint64), clips=join_clips(ordered)))
        self._ready.sort(key=lambda e: e.version)

    def poll(self) -> List[UpdateEvent]:
        """All complete updates received so far (non-blocking), oldest first."""
        with self._lock:
            if self._closed:
                return []
            self._drain()
            out, self._ready = self._ready, []
            return out

    def presence(self, timeout: float = 0.0) -> List[PresenceEvent]:
        """The presence changes received so far, oldest first (each returned once); waits up to
        ``timeout`` seconds for the first when there is none yet."""
        deadline = time.monotonic() + timeout
        with self._lock:
            while not self._closed:
                self._drain()
                if self._presence or time.monotonic() >= deadline:
                    break
                self._inbox.wait(max(0.0, deadline - time.monotonic()))
            out, self._presence = self._presence, []
            return out

    def get(self, timeout: Optional[float] = None) -> Optional[UpdateEvent]:
        """The next complete update, waiting up to ``timeout`` seconds (None: forever); None on timeout."""
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._lock:
            while not self._closed:
                self._drain()
                if self._ready:
                    return self._ready.pop(0)
                if deadline is None:
                    self._inbox.wait(1.0)
                else:
                    remaining = deadline - time.monotonic()
                    if remaining <= 0:
                        return None
                    self._inbox.wait(remaining)
        return None

    def __iter__(self) -> Iterator[UpdateEvent]:
        while not self._closed:
            ev = self.get(timeout=None)
            if ev is None:
                return
            yield ev
            if ev.cause == "close":
                return
