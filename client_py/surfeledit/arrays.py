"""Client-side argument checks and array plumbing shared by the session and the watcher.

The checks only look at shapes and dtypes before anything is sent; values (finite, non-zero
normals, positive radii, known ids) are validated by the server or the in-process core, which raise
the same typed errors (:mod:`surfeledit.errors`). Conventions: arrays are numpy, row-major;
positions / normals ``(P, 3) float64``, radii ``(P,) float64``, ids ``(P,) uint64``.
"""

from __future__ import annotations

from typing import Any, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import errors
from ._protocol import proto
from .compact import compact_surfels, is_compact

__all__ = ["ArrayLike", "Vec3Like", "SelectorLike", "as_int", "as_float", "VERSIONS", "INT32", "as_vec3", "vec3",
           "as_points", "as_radii", "as_ids", "concat", "join_surfels",
           "join_clips", "readonly", "NO_IDS"]

ArrayLike = Union[np.ndarray, Sequence[Any]]
Vec3Like = Union[Sequence[float], np.ndarray]
#: A sphere selector ``(center (3,), radius)`` or a box selector ``(center (3,), half_extents (3,))``.
SelectorLike = Tuple[Vec3Like, Any]

#: An empty, read-only (0,) uint64 id array (the default of result fields).
NO_IDS = np.zeros(0, np.uint64)
NO_IDS.setflags(write=False)


def as_int(value: Any, name: str, lo: int, hi: int) -> int:
    """``value`` as an integer in [lo, hi); InvalidArgumentError naming ``name`` when it is not integral or outside
    (the wire's integer fields have fixed widths: a wider value would fail to encode)."""
    try:
        v = int(value)
        integral = v == value if isinstance(value, (float, np.floating)) else True
    except (TypeError, ValueError, OverflowError) as e:
        raise errors.InvalidArgumentError(f"{name} must be an integer: {e}", name) from None
    if not integral:
        raise errors.InvalidArgumentError(f"{name} = {value}: not an integer", name)
    if not lo <= v < hi:
        raise errors.InvalidArgumentError(f"{name} = {v}: outside [{lo}, {hi})", name)
    return v


def as_float(value: Any, name: str) -> float:
    """``value`` as a float; InvalidArgumentError naming ``name`` when it is not a number (finiteness and ranges
    are the server's or the core's checks)."""
    try:
        return float(value)
    except (TypeError, ValueError) as e:
        raise errors.InvalidArgumentError(f"{name} must be a number: {e}", name) from None


#: The range of a version (the wire's uint64) and of a count such as iterations (the wire's 32-bit ``long``).
VERSIONS = (0, 2**64)
INT32 = (-2**31, 2**31)


def as_vec3(v: Vec3Like, name: str) -> np.ndarray:
    """A (3,) float64 vector; InvalidArgumentError naming ``name`` when not numeric or of another shape."""
    try:
        a = np.asarray(v, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise errors.InvalidArgumentError(f"{name} must be a numeric (3,) vector: {e}", name) from None
    if a.shape != (3,):
        raise errors.InvalidArgumentError(f"{name} must have shape (3,), got {a.shape}", name)
    return a


def vec3(v: Vec3Like, name: str) -> "proto.Vec3":
    """A (3,) vector as the wire's ``Vec3``; InvalidArgumentError naming ``name`` as :func:`as_vec3`."""
    a = as_vec3(v, name)
    return proto.Vec3(float(a[0]), float(a[1]), float(a[2]))


def as_points(a: ArrayLike, name: str, n: Optional[int] = None) -> np.ndarray:
    """``a`` as a C-contiguous (n, 3) float64 array; InvalidArgumentError naming ``name`` otherwise
    (not numeric, not (P, 3), or not ``n`` rows when ``n`` is given)."""
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise errors.InvalidArgumentError(f"{name} must be a numeric (P, 3) array: {e}", name) from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise errors.InvalidArgumentError(f"{name} must have shape (P, 3), got {arr.shape}", name)
    if n is not None and arr.shape[0] != n:
        raise errors.InvalidArgumentError(f"{name} has {arr.shape[0]} rows, positions has {n}", name)
    return np.ascontiguousarray(arr)


def as_radii(a: Optional[ArrayLike], n: int, name: str = "radii") -> Optional[np.ndarray]:
    """``a`` as (n,) float64 radii (None stays None); InvalidArgumentError naming ``name`` otherwise."""
    if a is None:
        return None
    rad = np.asarray(a, dtype=np.float64)
    if rad.ndim != 1 or rad.shape[0] != n:
        raise errors.InvalidArgumentError(f"{name} must have shape ({n},), got {rad.shape}", name)
    return rad


def as_ids(a: Optional[ArrayLike], name: str) -> List[int]:
    """``a`` (a (K,) integer array, a scalar or None) as a list of non-negative ids.

    Raises InvalidArgumentError naming ``name`` for another shape, a non-integer dtype or a negative id.
    """
    if a is None:
        return []
    arr = np.asarray(a)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise errors.InvalidArgumentError(f"{name} must be a 1-D array of ids, got shape {arr.shape}", name)
    if arr.size == 0:
        return []
    if not np.issubdtype(arr.dtype, np.integer):
        raise errors.InvalidArgumentError(f"{name} must hold integer ids, got dtype {arr.dtype}", name)
    if np.issubdtype(arr.dtype, np.signedinteger) and (arr < 0).any():
        raise errors.InvalidArgumentError(f"{name} holds a negative id", name)
    return arr.astype(np.uint64).tolist()


def concat(parts: Sequence[Any], field: str, dtype: Any) -> np.ndarray:
    """The sequence field ``field`` of every wire sample in ``parts`` joined into one flat array."""
    arrays = [np.asarray(getattr(p, field), dtype=dtype) for p in parts]
    return np.concatenate(arrays) if arrays else np.zeros(0, dtype)


def join_surfels(parts: Sequence[Any]) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(ids (N,) uint64, positions (N, 3), normals (N, 3), radii (N,) float64) of wire samples that
    carry surfels in pieces (state pages, update parts; either encoding), in the order given."""
    ids = concat(parts, "ids", np.uint64)
    if parts and is_compact(parts[0]):  # one reader reads one encoding: every part is compact then
        decoded = [compact_surfels(p) for p in parts]
        return (ids, np.concatenate([d[0] for d in decoded]), np.concatenate([d[1] for d in decoded]),
                np.concatenate([d[2] for d in decoded]))
    return (ids, concat(parts, "positions", np.float64).reshape(-1, 3),
            concat(parts, "normals", np.float64).reshape(-1, 3), concat(parts, "radii", np.float64))


def join_clips(parts: Sequence[Any]) -> Optional[np.ndarray]:
    """(N, 6) clip lines (point, direction) of wire samples that carry ``clip_points`` / ``clip_dirs``
    with their surfels, in the order given; None when they carry none (the model has no clip lines)."""
    points = concat(parts, "clip_points", np.float64)
    if points.size == 0:
        return None
    return np.hstack([points.reshape(-1, 3), concat(parts, "clip_dirs", np.float64).reshape(-1, 3)])


def readonly(arrays: Iterable[np.ndarray]) -> None:
    """Marks arrays read-only (results hand out views of caches)."""
    for a in arrays:
        a.setflags(write=False)
