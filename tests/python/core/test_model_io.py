"""Model I/O through PCL: round trips, meshes, normal estimation (shared models when present)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from surfeledit import core
from surfeledit.errors import NotFoundError, ServerIOError, InvalidArgumentError
from surfeledit.scenes import models_dir

MODELS = models_dir()  # $SURFELEDIT_MODELS or <repo>/../shared/data/models


def _need(name: str) -> Path:
    p = MODELS / name
    if not p.exists():
        pytest.skip(f"shared test model {p} not present")
    return p


@pytest.mark.parametrize("ext", [".ply", ".pcd"])
def test_round_trip_keeps_float64_positions(tmp_path: Path, ext: str) -> None:
    s = core.make_torus(0.5, 0.2, center=(1e6, -3e5, 7.0)).sample(spacing=0.05, seed=2)
    path = str(tmp_path / f"t{ext}")
    core.save_file(path, s.positions, s.normals, s.radii)
    d = core.load_file(path)
    np.testing.assert_array_equal(d["positions"], s.positions)
    np.testing.assert_allclose(d["normals"], s.normals, atol=1e-6)  # stored as float32
    np.testing.assert_allclose(d["radii"], s.radii, rtol=1e-6)


def _obj_area_weighted_normals(path: Path):
    """Independent reference: parse v/f lines with numpy, sum face cross products per vertex."""
    verts, faces = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    v = np.array(verts)
    acc = np.zeros_like(v)
    used = np.zeros(len(v), bool)
    for f in faces:
        for k in range(1, len(f) - 1):
            n = np.cross(v[f[k]] - v[f[0]], v[f[k + 1]] - v[f[0]])
            acc[[f[0], f[k], f[k + 1]]] += n
        used[f] = True
    keep = used & (np.linalg.norm(acc, axis=1) > 0)
    return v[keep], acc[keep] / np.linalg.norm(acc[keep], axis=1)[:, None]


@pytest.mark.parametrize("name", ["mug.obj", "spot.obj", "stanford-bunny.obj"])
def test_mesh_becomes_vertex_surfels(name: str) -> None:
    path = _need(name)
    d = core.load_file(str(path))
    ref_p, ref_n = _obj_area_weighted_normals(path)
    assert d["positions"].shape == ref_p.shape  # unreferenced vertices dropped
    np.testing.assert_allclose(d["positions"], ref_p, rtol=1e-6, atol=1e-6 * np.abs(ref_p).max())
    cos = np.sum(d["normals"] * ref_n, axis=1)
    assert np.mean(cos > 0.999) > 0.999
    assert (d["radii"] > 0).all()


def test_estimated_normals_are_consistently_oriented(tmp_path: Path) -> None:
    pwn = np.loadtxt(_need("elephant.pwn"))
    pts, truth = pwn[:, :3], pwn[:, 3:]
    path = tmp_path / "elephant.pcd"
    # A cloud without normals: write x y z only.
    header = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\n"
              f"WIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(pts)}\nDATA ascii\n")
    path.write_text(header + "\n".join(" ".join(f"{x:.17g}" for x in p) for p in pts) + "\n")
    d = core.load_file(str(path))
    cos = np.sum(d["normals"] * truth, axis=1)
    agree = float(np.mean(cos > 0))
    aligned = float(np.mean(np.abs(cos) > 0.9))
    print(f"elephant: {agree:.4f} oriented like the truth, {aligned:.4f} within 25 degrees of its line")
    assert agree >= 0.95
    assert aligned >= 0.8


def test_a_point_set_with_normals_loads_as_written() -> None:
    # elephant.pwn: x y z nx ny nz per line (read here by numpy, independently of PCL's reader).
    path = _need("elephant.pwn")
    truth = np.loadtxt(path)
    d = core.load_file(str(path))
    np.testing.assert_array_equal(d["positions"], truth[:, :3])
    unit = truth[:, 3:] / np.linalg.norm(truth[:, 3:], axis=1)[:, None]
    np.testing.assert_allclose(d["normals"], unit, atol=1e-12)
    assert d["radii"].shape == (len(truth),) and (d["radii"] > 0).all()


def test_errors_name_the_file(tmp_path: Path) -> None:
    with pytest.raises(NotFoundError, match="nope.ply"):
        core.load_file(str(tmp_path / "nope.ply"))
    bad = tmp_path / "bad.pcd"
    bad.write_text("this is not a point cloud\n")
    with pytest.raises(ServerIOError, match="bad.pcd"):
        core.load_file(str(bad))
    with pytest.raises(InvalidArgumentError, match="unsupported extension"):
        core.load_file(str(bad.with_suffix(".vtk").resolve()) if bad.with_suffix(".vtk").write_text("1 2 3") else "")
    nan = tmp_path / "nan.pcd"
    nan.write_text("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\n"
                   "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n0 0 0\nnan 0 0\n1 1 1\n")
    with pytest.raises((InvalidArgumentError, ServerIOError), match="nan.pcd"):
        core.load_file(str(nan))


@pytest.mark.parametrize("ext", [".ply", ".pcd"])
def test_truncated_files_are_rejected(tmp_path: Path, ext: str) -> None:
    s = core.make_sphere(1.0).sample(spacing=0.05)
    full = tmp_path / f"full{ext}"
    core.save_file(str(full), s.positions, s.normals, s.radii)
    data = full.read_bytes()
    for cut in (300, len(data) // 2):
        path = tmp_path / f"cut{cut}{ext}"
        path.write_bytes(data[:cut])
        with pytest.raises(ServerIOError, match=path.name):
            core.load_file(str(path))
