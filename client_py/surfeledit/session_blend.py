"""The blend tool's operations of the remote :class:`surfeledit.Session` (issue 10): blend, boolean (model B
sent as the client's chunked upload, consumed by OP_BOOLEAN) and hole filling. Semantics and arguments as
:class:`surfeledit.session_api.EditingSession`; the in-process twin is in :mod:`surfeledit.local`.
"""

from __future__ import annotations

from typing import Any, Optional


from . import errors
from ._protocol import proto
from .arrays import INT32, ArrayLike, as_float, as_ids, as_int
from .results import BlendResult, FillResult, MergeResult, blend_result, fill_result


__all__ = ["BlendOps"]


class BlendOps:
    """Mixin of :class:`surfeledit.Session` (uses its ``_request``, ``_upload`` and ``_merge_result``);
    watchers get the causes ``"blend"``, ``"boolean"`` and ``"fill_holes"``."""

    version: int

    def _request(self, op: "proto.Op", **args: Any) -> "proto.Reply":  # pragma: no cover - Session's
        raise NotImplementedError

    def _upload(self, positions: ArrayLike, normals: ArrayLike, radii: Optional[ArrayLike]) -> None:  # pragma: no cover
        raise NotImplementedError

    def _merge_result(self, reply: "proto.Reply", op: str) -> MergeResult:  # pragma: no cover
        raise NotImplementedError

    def blend(self, iterations: int = 50, range_factor: float = 4.0, dt: float = 0.1, repulsion: str = "weight",
              weight: str = "compact", only_grow: bool = False, adaptive: bool = False,
              neighbourhood: str = "cached", features: Optional[ArrayLike] = None,
              projection: str = "mls") -> BlendResult:
        """Blend tool (see :meth:`surfeledit.session_api.EditingSession.blend`)."""
        ids = as_ids(features, "features") if features is not None else []
        args = proto.Blend(iterations=as_int(iterations, "iterations", *INT32),
                           range_factor=as_float(range_factor, "range_factor"), dt=as_float(dt, "dt"),
                           repulsion=str(repulsion), weight=str(weight), only_grow=bool(only_grow),
                           adaptive=bool(adaptive), neighbourhood=str(neighbourhood),
                           has_features=features is not None, features=ids, projection=str(projection))
        reply = self._request(proto.Op.OP_BLEND, blend=args)
        if not reply.blend:
            raise errors.InternalServerError("BLEND reply without a blend result", "blend")
        return blend_result(reply.blend[0], int(reply.version))

    def boolean(self, op: str, positions: ArrayLike, normals: ArrayLike,
                radii: Optional[ArrayLike] = None) -> MergeResult:
        """Boolean with model B (see :meth:`surfeledit.session_api.EditingSession.boolean`); B goes up in
        chunks of the server's ``max_chunk_surfels`` (at most ``max_model_surfels``) before the op."""
        self._upload(positions, normals, radii)
        reply = self._request(proto.Op.OP_BOOLEAN, boolean_op=proto.BooleanOperation(op=str(op)))
        return self._merge_result(reply, "BOOLEAN")

    def fill_holes(self, max_diameter: float, iterations: int = 10,
                   boundary: Optional[ArrayLike] = None, projection: str = "mls") -> FillResult:
        """Hole filling (see :meth:`surfeledit.session_api.EditingSession.fill_holes`)."""
        ids = as_ids(boundary, "boundary") if boundary is not None else []
        args = proto.FillHoles(max_diameter=as_float(max_diameter, "max_diameter"),
                               iterations=as_int(iterations, "iterations", *INT32),
                               has_boundary=boundary is not None, boundary=ids, projection=str(projection))
        reply = self._request(proto.Op.OP_FILL_HOLES, fill_holes=args)
        if not reply.fill:
            raise errors.InternalServerError("FILL_HOLES reply without a fill result", "fill_holes")
        return fill_result(reply.fill[0], int(reply.version))
