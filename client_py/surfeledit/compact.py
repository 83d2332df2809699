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
    """Unit normals ``(N, 3)`` of octahedral coordinates ``uv`` ``(N, 2)`` int16 (times 32767)."""
    xy = np.asarray(uv, dtype=np.float64).reshape(-1, 2) / 32767.0
    z = 1.0 - np.abs(xy).sum(axis=1)
    lower = z < 0.0
    sign = np.where(xy[lower] < 0.0, -1.0, 1.0)
    xy[lower] = (1.0 - np.abs(xy[lower][:, ::-1])) * sign
    n = np.column_stack([xy, z])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


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
