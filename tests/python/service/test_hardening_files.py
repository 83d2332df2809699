"""OP_LOAD_FILE against a real server (issue 12, "Files"): only regular files below ``--data-root`` are
read; outside it, through a symlink or ``..``, and missing files get ONE indistinguishable error; lying
headers, a huge sparse file and a FIFO fail fast without stalling or bloating the server; loading runs
off the request thread, so other clients are served while a slow file is read."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path
from typing import Callable, List, Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit import core, errors

from .conftest import ServerProcess, connect_to, free_domain, server_executable

LYING_PCD = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2000000000\n"
             "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2000000000\nDATA ascii\n1 2 3\n")


def save_cloud(path: Path, n: int = 200, seed: int = 3) -> np.ndarray:
    """A random cloud with normals and radii saved at ``path``; returns its positions (n, 3)."""
    rng = np.random.default_rng(seed)
    pos = rng.normal(size=(n, 3))
    nrm = pos / np.linalg.norm(pos, axis=1, keepdims=True)
    core.save_file(str(path), pos, nrm, np.full(n, 0.05))
    return pos


def rss_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError("no VmRSS")


def expect_error(action: Callable[[], object], error: type, within: float = 3.0) -> errors.SurfelEditError:
    t0 = time.monotonic()
    with pytest.raises(error) as e:
        action()
    assert time.monotonic() - t0 < within
    assert e.value.field == "load_file.path", (e.value.field, e.value.message)
    return e.value


def test_loads_below_the_root_by_relative_and_absolute_path(client: surfeledit.Client, data_root: Path) -> None:
    pos = save_cloud(data_root / "cloud.ply")
    (data_root / "sub").mkdir()
    save_cloud(data_root / "sub" / "other.PLY", n=50)
    s = client.open_session("files")
    assert s.load_file("cloud.ply").surfels == len(pos)
    np.testing.assert_allclose(np.sort(s.state().positions, axis=0), np.sort(pos, axis=0))
    assert s.load_file(str(data_root / "sub" / "other.PLY")).surfels == 50
    assert s.load_file("sub/../cloud.ply").surfels == len(pos)  # .. that stays inside is fine


def test_outside_symlink_dotdot_and_missing_get_one_error(client: surfeledit.Client, data_root: Path,
                                                          tmp_path: Path) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    save_cloud(outside / "secret.ply")
    os.symlink(outside / "secret.ply", data_root / "link.ply")
    os.symlink(outside, data_root / "dirlink")
    s = client.open_session("probe")
    version = client.request(surfeledit.proto.Op.OP_INFO, "probe").version
    probes = {
        str(outside / "secret.ply"): "exists outside",
        "link.ply": "symlink escaping",
        "dirlink/secret.ply": "directory symlink escaping",
        "../outside/secret.ply": "dot-dot escaping",
        str(outside / "nothing.ply"): "missing outside",
        "nothing.ply": "missing inside",
        "/etc/../etc/nothing.ply": "missing elsewhere",
    }
    messages = {}
    for path, what in probes.items():
        e = expect_error(lambda: s.load_file(path), errors.NotFoundError)
        messages[what] = e.message.replace(path, "<path>")
        assert str(outside) not in e.message.replace(path, "") and str(data_root) not in e.message
    assert len(set(messages.values())) == 1, messages  # indistinguishable: nothing tells what exists
    assert client.request(surfeledit.proto.Op.OP_INFO, "probe").version == version
    assert s.info().surfels == 0


def test_fifo_and_directory_are_refused_without_stalling(client: surfeledit.Client, data_root: Path) -> None:
    os.mkfifo(data_root / "x.ply")
    os.mkfifo(data_root / "x.xyz")  # a text point set is read line by line to its end: a FIFO would never end
    (data_root / "d.ply").mkdir()
    s = client.open_session("fifo")
    for name in ("x.ply", "x.xyz", "d.ply"):
        e = expect_error(lambda: s.load_file(name), errors.InvalidArgumentError, within=2.0)
        assert "regular file" in e.message
    assert client.info().version  # still answering


def test_text_point_sets_load_as_written_and_malformed_ones_name_their_line(client: surfeledit.Client,
                                                                           data_root: Path) -> None:
    rng = np.random.default_rng(11)
    pos = rng.normal(size=(120, 3))
    nrm = pos / np.linalg.norm(pos, axis=1, keepdims=True)
    np.savetxt(data_root / "cloud.pwn", np.hstack([pos, nrm]), fmt="%.17g")
    np.savetxt(data_root / "plain.xyz", pos, fmt="%.17g", header="x y z")  # a '#' comment line first
    s = client.open_session("text")
    assert s.load_file("cloud.pwn").surfels == len(pos)
    st = s.state()
    order = np.argsort(st.positions[:, 0])
    truth = np.argsort(pos[:, 0])
    np.testing.assert_allclose(st.positions[order], pos[truth], rtol=0, atol=1e-12)
    np.testing.assert_allclose(st.normals[order], nrm[truth], rtol=0, atol=1e-12)
    assert s.load_file("plain.xyz").surfels == len(pos)  # normals estimated: only the count is checked here
    (data_root / "bad.xyz").write_text("0 0 0\n1 1 1 1\n2 2 2\n")
    (data_root / "nul.pwn").write_bytes(b"0 0 0 0 0 1\n1 1\x00 1 0 0 1\n")
    before = client.request(surfeledit.proto.Op.OP_INFO, "text")
    e = expect_error(lambda: s.load_file("bad.xyz"), errors.InvalidArgumentError)
    assert "line 2" in e.message and "bad.xyz" in e.message and str(data_root) not in e.message, e.message
    e = expect_error(lambda: s.load_file("nul.pwn"), errors.ServerIOError)
    assert "NUL" in e.message, e.message
    after = client.request(surfeledit.proto.Op.OP_INFO, "text")
    assert after.version == before.version  # refused: nothing changed
    assert after.session_info[0].state_hash == before.session_info[0].state_hash


OCTAHEDRON_FACES = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])


def test_meshes_in_off_and_stl_load_with_their_analytic_normals(client: surfeledit.Client, data_root: Path) -> None:
    # An octahedron around c: at vertex c + s e the area-weighted normal is e.
    c, scale = np.array([0.5, -2.0, 3.25]), 0.75
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    verts = c + scale * axes
    off = ["OFF", f"{len(verts)} {len(OCTAHEDRON_FACES)} 0"] + [" ".join(f"{x:.17g}" for x in v) for v in verts]
    off += [f"3 {a} {b} {d}" for a, b, d in OCTAHEDRON_FACES]
    (data_root / "octahedron.off").write_text("\n".join(off) + "\n")
    tri = np.zeros(len(OCTAHEDRON_FACES), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    tri["v"] = verts[OCTAHEDRON_FACES]  # float32: exact for these coordinates
    (data_root / "octahedron.stl").write_bytes(b"\0" * 80 + np.uint32(len(tri)).tobytes() + tri.tobytes())
    s = client.open_session("meshes")
    for name in ("octahedron.off", "octahedron.stl"):
        assert s.load_file(name).surfels == len(verts), name
        st = s.state()
        order = np.lexsort(st.positions.T)
        truth = np.lexsort(verts.T)
        np.testing.assert_allclose(st.positions[order], verts[truth], rtol=0, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(st.normals[order], axes[truth], rtol=0, atol=1e-12, err_msg=name)
    (data_root / "lying.off").write_text("OFF\n2000000000 1 0\n0 0 0\n")
    expect_error(lambda: s.load_file("lying.off"), (errors.TooLargeError, errors.ServerIOError))


def test_lying_headers_and_a_huge_sparse_file_fail_fast_with_bounded_memory(
        server: ServerProcess, client: surfeledit.Client, data_root: Path) -> None:
    (data_root / "lying.pcd").write_text(LYING_PCD)
    assert (data_root / "lying.pcd").stat().st_size < 200
    with open(data_root / "zeros.ply", "wb") as f:
        f.truncate(1 << 30)  # sparse: 1 GiB of zeros on no disk space
    s = client.open_session("lies")
    rss0 = rss_kb(server.proc.pid)
    expect_error(lambda: s.load_file("lying.pcd"), (errors.TooLargeError, errors.ServerIOError))
    e = expect_error(lambda: s.load_file("zeros.ply"), errors.ServerIOError)
    assert "not a PLY file" in e.message
    assert rss_kb(server.proc.pid) - rss0 < 64 * 1024  # KiB
    assert s.info().surfels == 0


def test_file_loading_is_off_without_a_data_root_and_files_beyond_the_limit_are_refused(tmp_path: Path) -> None:
    exe = server_executable()
    root = tmp_path / "root"
    root.mkdir()
    save_cloud(root / "big.ply", n=60000)  # about 2.6 MB
    assert (root / "big.ply").stat().st_size > (1 << 20)
    for args, error, words in (((), errors.ConflictError, "--data-root"),
                               (("--data-root", str(root), "--max-file-mb", "1"), errors.TooLargeError, "limit")):
        domain = free_domain()
        srv = ServerProcess(exe, domain, tmp_path / f"server-{domain}.log", None, args)
        try:
            c = connect_to(srv)
            s = c.open_session("s")
            e = expect_error(lambda: s.load_file(str(root / "big.ply")), error)
            assert words in e.message
            c.close()
        finally:
            srv.stop()


def write_slow_cloud(path: Path, n: int) -> None:
    """A binary PLY of ``n`` points without normals: loading it estimates and orients normals (seconds)."""
    rng = np.random.default_rng(11)
    theta, phi = rng.uniform(0, 2 * np.pi, n), np.arccos(rng.uniform(-1, 1, n))
    pts = np.stack([np.sin(phi) * np.cos(theta), np.sin(phi) * np.sin(theta), np.cos(phi)], axis=1)
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n").encode()
    path.write_bytes(header + pts.astype("<f4").tobytes())


def test_other_clients_are_served_while_a_slow_file_loads(server: ServerProcess, data_root: Path,
                                                         make_client: Callable[[], surfeledit.Client]) -> None:
    write_slow_cloud(data_root / "slow.ply", 400_000)
    other = make_client()
    # The loader waits as long as the load takes (the machine may be busy): no retry after 10 s.
    loader = surfeledit.connect(domain=server.domain, spawn=False, timeout=120.0)
    s = loader.open_session("slow")
    o = other.open_session("busy")
    done: List[float] = []
    failure: List[BaseException] = []

    def load() -> None:
        try:
            s.load_file("slow.ply")
        except BaseException as e:  # reported below
            failure.append(e)
        done.append(time.monotonic())

    t = threading.Thread(target=load)
    t0 = time.monotonic()
    t.start()
    served: List[Tuple[float, float]] = []  # (when answered, round trip s) while the load ran
    while t.is_alive() and time.monotonic() - t0 < 60:
        a = time.monotonic()
        o.info()
        b = time.monotonic()
        if not done:
            served.append((b, b - a))
        time.sleep(0.05)
    t.join(120)
    surfels = s.info().surfels if done and not failure else None
    loader.close()
    assert not failure, failure
    assert done and surfels == 400_000
    load_s = done[0] - t0
    in_time = [rtt for when, rtt in served if when < done[0]]
    assert load_s > 0.5, f"the load took only {load_s:.2f} s: too fast to show anything"
    assert len(in_time) >= 3, (load_s, served)
    assert max(in_time) < min(1.0, load_s / 2), (load_s, max(in_time))  # never waited for the load
    print(f"load {load_s:.2f} s; {len(in_time)} requests of another client served meanwhile, "
          f"max round trip {max(in_time) * 1e3:.0f} ms")
