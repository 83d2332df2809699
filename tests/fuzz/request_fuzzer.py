#!/usr/bin/env python3
"""Seeded structured fuzzer of the request handler, over raw DDS samples against a real server.

Each iteration sends one ``proto.Request`` built from the protocol's own types with values drawn from
edge cases (op numbers inside and outside ``Op``, enum kinds outside their enums, NaN/inf/1e308,
zero/huge counts and offsets, arguments missing, doubled or of another op, paths that escape the data
root, a FIFO, lying headers), interleaved with well-formed sessions (a small model loaded, regions set)
so that the deeper ops run too. Every request must get exactly one reply within ``--reply-timeout``
seconds whose status is not STATUS_INTERNAL and whose ``field`` names the input when it is an error;
the server must stay up with bounded memory. A violation prints the seed, the iteration and the
request, which then becomes a regression test (tests/python/service/test_fuzz_requests.py).

Usage (CI runs 45 s; longer on demand)::

    python tests/fuzz/request_fuzzer.py --seconds 600 --seed 7
"""

from __future__ import annotations

import argparse
import math
import os
import random
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, List, Optional

import numpy as np

import surfeledit
from surfeledit import core, proto
from surfeledit.server_process import spawn_server, stop_process

DOUBLES = [0.0, -0.0, 1.0, -1.0, 0.5, 3.14159, 1e-300, 5e-324, 1e6, -1e6, 1e200, 1e308, -1e308,
           math.inf, -math.inf, math.nan]
COUNTS = [0, 1, 2, 3, 5, 64, 2**31 - 1, 2**32, 2**63, 2**64 - 1]
INT32S = [0, 1, 2, 3, 7, 9, 17, 18, 99, -1, 2**31 - 1, -(2**31)]
SESSIONS = ["f0", "f1", ""]
PATHS = ["", "ok.ply", "lying.pcd", "fifo.ply", "zeros.ply", "../outside.ply", "/etc/passwd.ply",
         "sub/../../x.ply", "a" * 4096 + ".ply", "dir.ply", "ok.PLY", "notes.txt", "/dev/zero.ply",
         "lying.off", "face.off", "zeros.stl", "lying.stl", "fifo.xyz"]
BLENDS = ["smooth", "linear", "quadratic", "", "bogus", "SMOOTH"]


class Violation(AssertionError):
    """The server broke the reply guarantee (or died) on a request."""


class Fuzzer:
    def __init__(self, client: surfeledit.Client, seed: int, reply_timeout: float) -> None:
        self.client = client
        self.rng = random.Random(seed)
        self.seed = seed
        self.reply_timeout = reply_timeout
        self.settings = [str(s["name"]) for s in core.setting_specs()] + ["bogus", ""]
        self.texts = sorted({str(c) for s in core.setting_specs() for c in s.get("choices", [])} | {"", "x"})
        self.count = 0
        self.statuses: dict = {}

    # -- value generators --------------------------------------------------------------------
    def d(self) -> float:
        r = self.rng.random()
        return self.rng.choice(DOUBLES) if r < 0.6 else self.rng.uniform(-2.0, 2.0)

    def vec(self) -> "proto.Vec3":
        return proto.Vec3(self.d(), self.d(), self.d())

    def doubles(self, n: Optional[int] = None) -> List[float]:
        n = self.rng.choice([0, 1, 3, 6, 9, 12, 30]) if n is None else n
        return [self.d() for _ in range(n)]

    def ids(self) -> List[int]:
        return [self.rng.choice(COUNTS + list(range(10))) for _ in range(self.rng.choice([0, 1, 3, 20]))]

    def selector(self) -> "proto.Selector":
        kind = self.rng.choice([0, 1, 0, 1] + INT32S)
        return proto.Selector(kind=kind, center=self.vec(), radius=self.d(), half_extents=self.vec())

    def region(self) -> "proto.RegionSpec":
        return proto.RegionSpec(ids=self.ids(), selectors=[self.selector() for _ in range(self.rng.choice([0, 1, 2]))])

    def setting(self) -> "proto.Setting":
        return proto.Setting(name=self.rng.choice(self.settings), kind=self.rng.choice([0, 1, 2, 3, 3, 9, -1]),
                             number=self.rng.choice([self.d(), float(self.rng.choice(INT32S))]),
                             flag=self.rng.random() < 0.5, text=self.rng.choice(self.texts))

    def argument(self, op: int) -> dict:
        """The op's argument field (sometimes missing, doubled, or another op's)."""
        makers: dict = {
            "load_begin": lambda: proto.LoadBegin(total=self.rng.choice(COUNTS), has_radii=self.rng.random() < 0.5),
            "load_chunk": lambda: proto.LoadChunk(offset=self.rng.choice(COUNTS), positions=self.doubles(),
                                                  normals=self.doubles(), radii=self.doubles()),
            "load_file": lambda: proto.LoadFile(path=self.rng.choice(PATHS)),
            "set_regions": lambda: proto.SetRegions(zero=self.region(), one=self.region()),
            "deform": lambda: proto.Deform(translation=self.vec(), axis=self.vec(), angle=self.d(),
                                           has_center=self.rng.random() < 0.5, center=self.vec(),
                                           blend=self.rng.choice(BLENDS)),
            "get_state": lambda: proto.GetState(changes_only=self.rng.random() < 0.5,
                                                since_version=self.rng.choice(COUNTS),
                                                offset=self.rng.choice(COUNTS), max_count=self.rng.choice(COUNTS)),
            "configure": lambda: proto.Configure(settings=[self.setting() for _ in range(self.rng.choice([0, 1, 2, 4]))]),
            "remove": lambda: proto.Remove(ids=self.ids()),
            "merge": lambda: proto.Merge(crease=self.rng.random() < 0.5),
            "curves": lambda: proto.Curves(refine_angle=self.d()),
        }
        own = {4: "load_begin", 5: "load_chunk", 7: "load_file", 8: "set_regions", 9: "deform", 10: "get_state",
               11: "configure", 12: "remove", 16: "merge", 17: "curves"}.get(op)
        r = self.rng.random()
        name = own if own and r < 0.8 else self.rng.choice(sorted(makers))
        n = 1 if r < 0.9 else self.rng.choice([0, 2])
        return {name: [makers[name]() for _ in range(n)]}

    # -- driving ------------------------------------------------------------------------------
    def send(self, req: "proto.Request") -> "proto.Reply":
        t0 = time.monotonic()
        try:
            reply = self.client.call(req, check=False, timeout=self.reply_timeout, retries=0)
        except surfeledit.errors.RequestTimeoutError as e:
            raise Violation(f"no reply within {self.reply_timeout} s: {e}") from None
        status = int(reply.status.value)
        self.statuses[status] = self.statuses.get(status, 0) + 1
        if status == int(proto.Status.STATUS_INTERNAL):
            raise Violation(f"STATUS_INTERNAL ({reply.field!r}: {reply.message})")
        if status != 0 and not reply.field:
            raise Violation(f"error status {status} without a field: {reply.message}")
        if time.monotonic() - t0 > self.reply_timeout:
            raise Violation("reply too late")
        return reply

    def well_formed_session(self) -> None:
        """A small real model with regions in session f0 (so that deeper ops have something to act on)."""
        s = self.client.open_session("f0")
        n = self.rng.choice([40, 200])
        rng = np.random.default_rng(self.rng.randrange(2**32))
        pos = rng.normal(size=(n, 3))
        pos[: n // 2, 2] -= 3.0
        nrm = pos / np.linalg.norm(pos, axis=1, keepdims=True)
        s.load_points(pos, nrm, np.full(n, 0.2))
        ids = s.ids()
        s.set_regions(zero=ids[: n // 2], one=ids[n // 2:])

    def step(self) -> "proto.Request":
        if self.count % 60 == 0:
            self.well_formed_session()
        op = self.rng.choice(list(range(18)) * 4 + INT32S)
        session = self.rng.choice(SESSIONS + ["f0", "f0"])
        req = self.client.new_request(proto.Op.OP_INFO, session)
        req.op = op
        for name, value in self.argument(op).items():
            setattr(req, name, value)
        if self.rng.random() < 0.05 and self.count > 0:
            req.request_id = max(1, req.request_id - self.rng.choice([1, 2, 5]))  # a repeat
        self.count += 1
        self.send(req)
        return req


def make_data_root(root: Path) -> None:
    """Files for the load_file paths: a valid cloud, lying headers, sparse GiBs of zeros, FIFOs, a directory."""
    rng = np.random.default_rng(0)
    pos = rng.normal(size=(100, 3))
    core.save_file(str(root / "ok.ply"), pos, pos / np.linalg.norm(pos, axis=1, keepdims=True), np.full(100, 0.1))
    (root / "lying.pcd").write_text("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                                    "WIDTH 2000000000\nHEIGHT 1\nPOINTS 2000000000\nDATA ascii\n1 2 3\n")
    with open(root / "zeros.ply", "wb") as f:
        f.truncate(1 << 30)
    os.mkfifo(root / "fifo.ply")
    os.mkfifo(root / "fifo.xyz")
    (root / "dir.ply").mkdir()
    # Meshes read by CGAL: counts beyond the file, a face's size beyond any mesh, a sparse GiB, a binary STL header
    # announcing 2^32 - 1 triangles in 84 bytes.
    (root / "lying.off").write_text("OFF\n2000000000 2000000000 0\n0 0 0\n")
    (root / "face.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n")
    with open(root / "zeros.stl", "wb") as f:
        f.truncate(1 << 30)
    (root / "lying.stl").write_bytes(b"\0" * 80 + (0xFFFFFFFF).to_bytes(4, "little"))


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return 0.0


def run(seconds: float, seed: int, domain: int, reply_timeout: float = 10.0, max_rss_mb: float = 2048.0,
        log: Callable[[str], Any] = print) -> dict:
    """Fuzzes a fresh server on ``domain`` for ``seconds``; returns counts. Raises Violation on a finding."""
    with tempfile.TemporaryDirectory(prefix="surfeledit-fuzz-") as tmp:
        root = Path(tmp) / "root"
        root.mkdir()
        make_data_root(root)
        proc, server_log = spawn_server(domain, root)
        client = None
        fuzzer = None
        req = None
        try:
            deadline = time.monotonic() + 20
            while True:
                try:
                    client = surfeledit.connect(domain=domain, spawn=False, timeout=reply_timeout)
                    break
                except surfeledit.ServerStartError:
                    if time.monotonic() > deadline or proc.poll() is not None:
                        raise
            fuzzer = Fuzzer(client, seed, reply_timeout)
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                req = None
                if proc.poll() is not None:
                    raise Violation(f"the server exited with code {proc.returncode}")
                req = fuzzer.step()
            if proc.poll() is not None:
                raise Violation(f"the server exited with code {proc.returncode}")
            rss = rss_mb(proc.pid)
            if rss > max_rss_mb:
                raise Violation(f"server RSS {rss:.0f} MB beyond {max_rss_mb:.0f} MB")
            result = {"requests": fuzzer.count, "statuses": dict(sorted(fuzzer.statuses.items())), "rss_mb": rss}
            log(f"request fuzzer: seed {seed}, {fuzzer.count} requests in {seconds:.0f} s, statuses {result['statuses']}, "
                f"server RSS {rss:.0f} MB")
            return result
        except Violation as e:
            tail = server_log.read_text(errors="replace")[-3000:]
            raise Violation(f"seed {seed}, request #{fuzzer.count if fuzzer else 0}: {e}\nrequest: {req!r}\n"
                            f"server log tail:\n{tail}") from None
        finally:
            if client is not None:
                try:
                    client.close()
                except Exception:  # the server may be gone: nothing to close
                    pass
            stop_process(proc)


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=45.0, help="how long to fuzz (default 45)")
    ap.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    ap.add_argument("--domain", type=int, default=None, help="DDS domain (default: one this process holds)")
    args = ap.parse_args(argv)
    if args.domain is None:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
        from service import domains  # one lock file per domain: no test run or benchmark uses it meanwhile
        domain = domains.take()  # held until this process exits
    else:
        domain = args.domain
    try:
        run(args.seconds, args.seed, domain)
    except Violation as e:
        print(f"FINDING: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
