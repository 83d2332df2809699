"""1M surfels: chunked load and paged fetch round trip against a real server."""

from __future__ import annotations

import time

import numpy as np
import pytest

import surfeledit

N = 1_000_000


@pytest.mark.large
def test_one_million_surfels_round_trip(client: surfeledit.Client) -> None:
    rng = np.random.default_rng(7)
    nrm = rng.normal(size=(N, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    pos = 2.0 * nrm  # a sphere of radius 2 model units
    rad = np.full(N, 0.004)
    with client.open_session("big") as s:
        t0 = time.perf_counter()
        info = s.load_points(pos, nrm, rad)
        t1 = time.perf_counter()
        st = s.state()
        t2 = time.perf_counter()
        print(f"\n1M surfels: load {t1 - t0:.2f} s ({N / (t1 - t0) / 1e6:.2f} M/s), "
              f"fetch {t2 - t1:.2f} s ({N / (t2 - t1) / 1e6:.2f} M/s), "
              f"server bytes/surfel {info.bytes_per_surfel:.1f}")
        assert info.surfels == N
        assert len(st) == N
        np.testing.assert_array_equal(st.ids, np.arange(N, dtype=np.uint64))
        np.testing.assert_array_equal(st.positions, pos)
        np.testing.assert_allclose(st.normals, nrm, atol=1e-12)
        np.testing.assert_array_equal(st.radii, rad)
        t3 = time.perf_counter()
        assert s.state() is st  # unchanged version: served from the cache with one small request
        assert time.perf_counter() - t3 < 1.0
        assert t2 - t0 < 60.0, f"1M round trip took {t2 - t0:.1f} s"
