"""Decoding the compact encoding of updates (proto/PROTOCOL.md "Updates, compact"): float32 position
offsets from a per-part origin, octahedral int16 normals and float32 radii, as little-endian blobs.

Error bounds (the server's encoder, server/service/include/surfeledit/service/update_compact.hpp):
per coordinate at most 2^-25 times the part's bounding-box extent along that axis plus the doubles' own
rounding (2^-52 times the coordinate); normals within
:data:`OCTAHEDRAL_MAX_ANGLE` radians; radii within a relative 2^-24.
"""

from __future__ import annotations

from typing import Any, Tuple

import numpy as np

__all__ = ["OCTAHEDRAL_MAX_ANGLE", "is_compact", "octahedral_decode", "compact_surfels"]

#: Largest angle (radians) between a normal and its octahedral int16 encoding, decoded.
OCTAHEDRAL_MAX_ANGLE = 1e-4


def is_compact(sample: Any) -> bool:
    """Whether a wire sample carries its surfels in the compact encoding."""
    return len(getattr(sample, "origin", ())) == 3


def octahedral_decode(uv: np.ndarray) -> np.ndarray:
    """Unit normals ``(N, 3)`` of octahedral coordinates ``uv`` ``(N, 2)`` int16 (times 32767).

    Column by column, without masked copies or reductions along rows (each measured slower than the arithmetic):
    the lower half folds onto the upper as (1 - |y|, 1 - |x|) with the signs of (x, y), then each row is divided by
    its length, summed as x^2 + y^2 + z^2 in that order."""
    xy = np.asarray(uv, dtype=np.float64).reshape(-1, 2) / 32767.0
    x, y = xy[:, 0], xy[:, 1]
    ax, ay = np.abs(x), np.abs(y)
    z = 1.0 - (ax + ay)
    lower = z < 0.0
    fx = np.where(lower, (1.0 - ay) * np.where(x < 0.0, -1.0, 1.0), x)
    fy = np.where(lower, (1.0 - ax) * np.where(y < 0.0, -1.0, 1.0), y)
    length = np.sqrt((fx * fx + fy * fy) + z * z)
    n = np.empty((len(z), 3))
    n[:, 0] = fx / length
    n[:, 1] = fy / length
    n[:, 2] = z / length
    return n


def _blob(octets: Any) -> bytes:
    """The bytes of a ``sequence<octet>`` field (a uint8 array, wire_arrays.py, or the binding's list of ints)."""
    return octets if isinstance(octets, (bytes, bytearray)) else bytes(octets)


def compact_surfels(sample: Any) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions (n, 3) float64, normals (n, 3) float64, radii (n,) float64) of one compact sample."""
    origin = np.asarray(sample.origin, dtype=np.float64)
    offsets = np.frombuffer(_blob(sample.positions_f32), dtype="<f4").reshape(-1, 3)
    positions = offsets.astype(np.float64) + origin
    normals = octahedral_decode(np.frombuffer(_blob(sample.normals_oct16), dtype="<i2"))
    radii = np.frombuffer(_blob(sample.radii_f32), dtype="<f4").astype(np.float64)
    return positions, normals, radii
