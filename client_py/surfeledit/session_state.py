"""Reading the model of a remote :class:`surfeledit.Session`: GET_STATE answers of one version, read page
by page (:meth:`StateOps.state`, :meth:`StateOps.changes_since`); the last full state is cached by version.
"""

from __future__ import annotations

import logging
from typing import Any, List, Optional, Tuple

import numpy as np

from . import errors
from ._protocol import proto
from .arrays import VERSIONS, as_int, join_clips, join_surfels, readonly
from .results import Changes, State, clips_or_none, merge

__all__ = ["StateOps"]

_log = logging.getLogger("surfeledit")
_FETCH_ATTEMPTS = 8  # GET_STATE restarts when the version moves between pages


class StateOps:
    """Mixin of :class:`surfeledit.Session` (uses its ``_request``, ``name``, ``version`` and ``_cache``)."""

    name: str
    version: int
    _cache: Optional[State]

    def _request(self, op: "proto.Op", expect_version: Optional[int] = None,
                 **args: Any) -> "proto.Reply":  # pragma: no cover - Session's
        raise NotImplementedError

    def _fetch_pages(self, changes_only: bool, since: int) -> Optional[Tuple[int, List["proto.StatePage"]]]:
        """(version, all pages) of one GET_STATE answer at one version; None if the version moved in between."""
        pages: List["proto.StatePage"] = []
        version: Optional[int] = None
        offset = 0
        while True:
            reply = self._request(proto.Op.OP_GET_STATE, get_state=proto.GetState(
                changes_only=changes_only, since_version=since, offset=offset, max_count=0))
            if not reply.state:
                raise errors.InternalServerError("GET_STATE reply without a state page", "state")
            page = reply.state[0]
            if version is None:
                version = int(reply.version)
            elif int(reply.version) != version:
                return None
            pages.append(page)
            offset = int(page.offset) + len(page.ids)
            if offset >= int(page.total):
                return version, pages
            if len(page.ids) == 0:
                raise errors.InternalServerError(f"empty state page at offset {offset} of {page.total}", "state")

    def _fetch(self, changes_only: bool, since: int) -> Changes:
        """Reads all pages of one GET_STATE answer; restarts if the version moves between pages."""
        for _attempt in range(_FETCH_ATTEMPTS):
            answer = self._fetch_pages(changes_only, since)
            if answer is None:
                _log.debug("session %r changed while paging; restarting the fetch", self.name)
                continue
            version, pages = answer
            ids, pos, nrm, rad = join_surfels(pages)
            return Changes(version=version, full=bool(pages[0].full), ids=ids, positions=pos,
                           normals=nrm, radii=rad, removed=np.asarray(pages[0].removed, dtype=np.uint64),
                           clips=join_clips(pages))
        raise errors.ConflictError(f"session {self.name!r} kept changing while its state was fetched", "version")

    def changes_since(self, version: int) -> Changes:
        """Surfels changed or inserted since ``version`` plus removed ids (whole model if replaced)."""
        return self._fetch(True, as_int(version, "version", *VERSIONS))

    def state(self) -> State:
        """The whole model at the current version (arrays read-only).

        The last full fetch is cached by version; later calls fetch only the changes since then.
        """
        cache = self._cache
        if cache is None:
            ch = self._fetch(False, 0)
            new = State(ch.version, ch.ids, ch.positions, ch.normals, ch.radii, clips_or_none(ch.clips))
        else:
            ch = self._fetch(True, cache.version)
            if ch.version == cache.version and ch.ids.size == 0 and ch.removed.size == 0:
                return cache
            new = (State(ch.version, ch.ids, ch.positions, ch.normals, ch.radii, clips_or_none(ch.clips)) if ch.full
                   else merge(cache, ch))
        readonly((new.ids, new.positions, new.normals, new.radii) + ((new.clips,) if new.clips is not None else ()))
        self._cache = new
        self.version = new.version
        return new
