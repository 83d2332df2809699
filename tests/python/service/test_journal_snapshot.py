"""Journal snapshots (issue 11 §5, docs/journal.md): recovery restores the newest snapshot and replays
only the records after it, and the result is the server that never restarted. The independent truth
is a second server process without a journal that gets the same ops from clients with the same ids:
state hash, version and OP_HISTORY agree after the restart, then the same further ops (per-client
undo and redo, a refused undo) give the same outcomes on both. A corrupt, truncated or missing
snapshot file falls back (older snapshot or the log's start) and still recovers exactly; a session
that is not snapshottable keeps full replay."""

from __future__ import annotations

import re
import shutil
import time
from pathlib import Path
from typing import Callable, Dict, List, Tuple

import numpy as np

import surfeledit
from surfeledit import errors
from surfeledit._protocol import proto

from .conftest import ServerProcess, free_domain, server_executable
from .test_tools import claim_arms, two_arms

SNAPSHOT_RECORDS = 7


def _server(tmp_path: Path, name: str, domain: int, *extra: str) -> ServerProcess:
    srv = ServerProcess(server_executable(), domain, tmp_path / f"{name}.log", extra=("--threads", "1") + extra)
    srv.wait_ready(20.0)
    return srv


def _restart(servers: List[ServerProcess], tmp_path: Path, name: str, domain: int, *extra: str) -> ServerProcess:
    """Kills the newest of ``servers`` with SIGKILL and starts another (appended: the test stops them all)."""
    servers[-1].proc.kill()
    servers[-1].proc.wait()
    servers.append(_server(tmp_path, name, domain, *extra))
    return servers[-1]


def settled(srv: ServerProcess, timeout: float = 60.0) -> int:
    """Waits until every snapshot the server started was written or failed (the writer thread finished
    it and the request thread journaled its record or logged why not), seen twice 0.2 s apart (a finished
    snapshot may start the next one at once); returns how many were taken."""
    end, last = time.monotonic() + timeout, None
    while time.monotonic() < end:
        log = srv.log_tail(10**8)
        started = len(re.findall(r"snapshot \d+ started", log))
        ended = len(re.findall(r"snapshot \d+ (?:taken|not written)", log))
        if started == ended and last == started:
            return len(re.findall(r"snapshot \d+ taken", log))
        last = started if started == ended else None
        time.sleep(0.2)
    raise AssertionError(f"snapshots still in flight after {timeout} s:\n{srv.log_tail()}")


def wait_for(condition: Callable[[], bool], what: str, timeout: float = 30.0) -> None:
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, what
        time.sleep(0.05)


def _journal_flags(journal: Path) -> Tuple[str, ...]:
    return ("--journal", str(journal), "--journal-snapshot-records", str(SNAPSHOT_RECORDS))


def _recovery(srv: ServerProcess) -> Tuple[int, int]:
    """(snapshot restored or 0, records replayed) from the server's recovery line."""
    log = srv.log_tail(10**7)
    m = re.search(r"recovered .*: (?:snapshot (\d+) restored|no snapshot).*?, (\d+) record\(s\) replayed", log)
    assert m, log[-2000:]
    return int(m.group(1) or 0), int(m.group(2))


def _frames(log: Path) -> int:
    """Records in one log segment, counted from its framing (16-byte header; u32 length, u32 CRC, u8 kind)."""
    data = log.read_bytes()
    at, n = 16, 0
    while at + 9 <= len(data):
        at += 9 + int.from_bytes(data[at:at + 4], "little")
        n += 1
    assert at == len(data)
    return n


def _segments(journal: Path) -> List[Path]:
    """The log segments holding records (not one the writer thread created ahead: its header alone)."""
    return [p for p in journal.glob("journal*.log") if p.stat().st_size > 16]


def _segment_number(p: Path) -> int:
    """k of ``journal-<k>.log``; 0 for the first segment, ``journal.log``. (Not the file's mtime: two
    segments written within one tick of the kernel's coarse clock have equal mtimes.)"""
    m = re.fullmatch(r"journal(?:-(\d+))?\.log", p.name)
    assert m, p
    return int(m.group(1) or 0)


def _history(s: surfeledit.Session) -> List[tuple]:
    return [(h.version, h.op, h.client, tuple(int(i) for i in h.touched), h.undone) for h in s.history()]


def _view(s: surfeledit.Session) -> tuple:
    info = s.info()
    return int(s.version), int(info.state_hash), _history(s)


class Pair:
    """The same clients (ids) on the reference server and on the journaled one."""

    def __init__(self, ref_domain: int, j_domain: int) -> None:
        self.domains = (ref_domain, j_domain)
        self.clients: Dict[str, List[surfeledit.Client]] = {}
        for who in ("alice", "bob"):
            self.clients[who] = [surfeledit.connect(domain=d, spawn=False, timeout=10.0, reconnect=30.0,
                                                    client_id=f"{who}-snap") for d in (ref_domain, j_domain)]
        self.sessions: Dict[str, List[surfeledit.Session]] = {}

    def both(self, who: str, fn: Callable[[surfeledit.Session], object]) -> List[object]:
        """Runs `fn` on `who`'s session on both servers: the results, or the refusals' (type, field, message)."""
        out = []
        for s in self.sessions[who]:
            try:
                out.append(fn(s))
            except errors.SurfelEditError as e:
                out.append((type(e).__name__, e.field, str(e)))
        assert out[0] == out[1], out
        return out

    def open_arms(self) -> Tuple[np.ndarray, np.ndarray]:
        """On both servers: alice opens session "snap" with the two-arm scene, bob joins as an editor, each
        claims an arm. Returns (ids, part) of the scene."""
        positions, normals, radii, part = two_arms()
        ids = np.arange(len(part))
        for k in range(2):
            a = self.clients["alice"][k].open_session("snap")
            a.load_points(positions, normals, radii)
            b = self.clients["bob"][k].join_session("snap", token=a.invite("editor"))
            self.sessions.setdefault("alice", []).append(a)
            self.sessions.setdefault("bob", []).append(b)
            claim_arms(a, b, ids, part)
        return ids, part

    def all(self) -> List[surfeledit.Client]:
        return [c for pair in self.clients.values() for c in pair]


def stop_all(servers: List[ServerProcess], *clients: surfeledit.Client) -> None:
    """Teardown: closes the clients (not reconnecting any more), then stops every server."""
    for c in clients:
        c.reconnect = 0.0
        c.close()
    for s in servers:
        s.stop()


def _step(s: surfeledit.Session, t: Tuple[float, float, float]) -> tuple:
    r = s.deform(translation=t)
    return int(r.version), tuple(int(i) for i in r.colliding)


def test_recovery_from_snapshot_and_tail_equals_a_server_that_never_restarted(tmp_path: Path) -> None:
    ref_domain, j_domain = free_domain(), free_domain()
    journal = tmp_path / "journal"
    ref = _server(tmp_path, "reference", ref_domain)
    srv = _server(tmp_path, "journaled-0", j_domain, *_journal_flags(journal))
    servers = [ref, srv]
    pair = Pair(ref_domain, j_domain)
    try:
        ids, part = pair.open_arms()
        # A request early in the log, long before the last snapshot: its repeat must be answered from the
        # reply store the snapshot restored (its record is not replayed).
        early = []
        for c in pair.clients["alice"]:
            req = c.new_request(proto.Op.OP_DEFORM, "snap", deform=proto.Deform(
                translation=proto.Vec3(0.01, 0.0, 0.0), axis=proto.Vec3(0.0, 0.0, 1.0), blend="smooth"))
            early.append((req, c.call(req)))
        assert early[0][1].version == early[1][1].version
        for i in range(9):  # the two arms swing towards each other: collisions, responses, history
            pair.both("alice", lambda s: _step(s, (0.02, 0.0, 0.002 * (i % 3))))
            pair.both("bob", lambda s: _step(s, (-0.02, 0.0, -0.002 * (i % 2))))
            if i == 4:
                pair.both("alice", lambda s: s.undo())
                pair.both("alice", lambda s: s.redo())
        pair.both("bob", lambda s: s.configure(response="cancel") and None)
        pair.both("bob", lambda s: _step(s, (-0.03, 0.0, 0.0)))
        before = [_view(s) for s in pair.sessions["alice"]]
        assert before[0] == before[1]
        records = int(before[1][0]) + 8  # at least one record per version, plus opens, invites, joins
        settled(srv)
        # The writer thread deletes what the newest snapshot made obsolete once its record is durable.
        wait_for(lambda: len(list(journal.glob("snapshot-*.bin"))) <= 2 and len(_segments(journal)) <= 2,
                 "older snapshots and segments are deleted")
        srv = _restart(servers, tmp_path, "journaled-1", j_domain, *_journal_flags(journal))
        snapshot, replayed = _recovery(srv)
        assert snapshot >= 2, "the script spans several snapshots"
        assert 0 < replayed <= SNAPSHOT_RECORDS, f"only the tail is replayed, not {replayed} of ~{records} records"

        # The same state, version and history as the server that never restarted.
        after = [_view(s) for s in pair.sessions["alice"]]
        assert after[1] == after[0] == before[0]
        # The early request's repeat: the stored reply (same version), not applied again.
        again = pair.clients["alice"][1].call(early[1][0])
        assert again.version == early[1][1].version and again.status == proto.Status.STATUS_OK
        assert pair.sessions["alice"][1].info().state_hash == after[0][1]

        # The same future: steps, per-client undo / redo, and an undo refused because of the other's later op.
        pair.both("alice", lambda s: _step(s, (0.0, 0.01, 0.0)))
        pair.both("bob", lambda s: _step(s, (0.0, -0.01, 0.0)))
        pair.both("alice", lambda s: s.undo())
        pair.both("bob", lambda s: s.undo())
        pair.both("bob", lambda s: s.redo())
        arm_a, arm_b, body = ids[part == 1], ids[part == 2], ids[part == 0]
        pair.both("alice", lambda s: s.release() and None)
        pair.both("bob", lambda s: s.release() and None)
        pair.both("bob", lambda s: s.set_regions(zero=np.concatenate([body, arm_b]), one=arm_a) and None)
        pair.both("bob", lambda s: _step(s, (0.0, 0.0, 0.02)))
        pair.both("bob", lambda s: s.release() and None)
        pair.both("alice", lambda s: s.undo())  # its release
        refused = pair.both("alice", lambda s: s.undo())  # its redone step: bob's later step overlaps
        assert refused[0][0] == "ConflictError" and "bob-snap" in refused[0][2]
        final = [_view(s) for s in pair.sessions["bob"]]
        assert final[0] == final[1]
        np.testing.assert_array_equal(pair.sessions["bob"][0].state().positions,
                                      pair.sessions["bob"][1].state().positions)

        # Fallbacks, each on a copy of the journal: the newest snapshot corrupt, truncated or missing.
        srv.stop()
        want = final[0]
        newest = max(journal.glob("snapshot-*.bin"), key=lambda p: int(p.stem.split("-")[1]))
        for n, (what, damage) in enumerate([
                ("corrupt", lambda p: p.write_bytes(p.read_bytes()[:100] + bytes([p.read_bytes()[100] ^ 1])
                                                    + p.read_bytes()[101:])),
                ("truncated", lambda p: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])),
                ("missing", lambda p: p.unlink())]):
            copy = tmp_path / f"journal-{what}"
            shutil.copytree(journal, copy)
            damage(copy / newest.name)
            domain = free_domain()
            other = _server(tmp_path, f"fallback-{what}", domain, "--journal", str(copy))
            servers.append(other)
            log = other.log_tail(10**7)
            assert f"snapshot {newest.stem.split('-')[1]} (record" in log and "not restored" in log, what
            restored, replayed = _recovery(other)
            assert restored < int(newest.stem.split("-")[1]) and replayed >= SNAPSHOT_RECORDS, what
            c = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, client_id="bob-snap")
            # A new process of bob's: its request ids come after the old ones the recovered store holds.
            try:
                assert _view(c.join_session("snap")) == want, what
            finally:
                c.close()
    finally:
        stop_all(servers, *pair.all())


def test_a_session_that_is_not_snapshottable_keeps_full_replay(tmp_path: Path) -> None:
    domain = free_domain()
    journal = tmp_path / "journal"
    srv = _server(tmp_path, "hier-0", domain, "--journal", str(journal), "--journal-snapshot-records", "3")
    servers = [srv]
    c = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, reconnect=30.0, client_id="hier")
    try:
        positions, normals, radii, part = two_arms()
        ids = np.arange(len(part))
        s = c.open_session("hier")
        s.load_points(positions, normals, radii)  # snapshots may be taken until the hierarchy is set
        s.configure(zero_hierarchy="aabb")
        settled(srv)
        taken = sorted(journal.glob("snapshot-*.bin"))
        segment = max(_segments(journal), key=_segment_number)
        s.set_regions(zero=ids[part != 1], one=ids[part == 1])
        for i in range(5):
            s.deform(translation=(0.01, 0.0, 0.001 * i))
        before = _view(s)
        assert "snapshot deferred (session 'hier'" in srv.log_tail(10**7)
        assert sorted(journal.glob("snapshot-*.bin")) == taken  # none since: the log keeps every record
        srv = _restart(servers, tmp_path, "hier-1", domain, "--journal", str(journal), "--journal-snapshot-records", "3")
        # Every record since the last snapshot (or the log's start) is replayed.
        snapshot, replayed = _recovery(srv)
        assert snapshot == max((int(p.stem.split("-")[1]) for p in taken), default=0) and replayed == _frames(segment)
        assert replayed >= 7
        assert _view(s) == before
    finally:
        stop_all(servers, c)


def test_a_snapshot_is_taken_when_the_log_exceeds_its_byte_bound(tmp_path: Path) -> None:
    """--journal-snapshot-mb alone: the upload's chunk records pass 1 MiB, so the next request after the
    commit takes a snapshot (none while the upload is unfinished); recovery restores it and replays the rest."""
    domain = free_domain()
    journal = tmp_path / "journal"
    args = ("--journal", str(journal), "--journal-snapshot-mb", "1")
    srv = _server(tmp_path, "mb-0", domain, *args)
    servers = [srv]
    c = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, reconnect=30.0, client_id="mb")
    try:
        rng = np.random.default_rng(5)
        n = 30_000  # positions and normals: 30k * 48 bytes, about 1.4 MiB of chunk records
        positions = rng.uniform(-1.0, 1.0, (n, 3))
        normals = positions / np.linalg.norm(positions, axis=1, keepdims=True)
        s = c.open_session("mb")
        s.load_points(positions, normals)
        log = srv.log_tail(10**7)
        assert "snapshot deferred (1 upload(s) unfinished)" in log
        s.remove(np.arange(3))
        before = _view(s)
        settled(srv)
        assert "snapshot 1 taken" in srv.log_tail(10**7) and (journal / "snapshot-1.bin").exists()
        srv = _restart(servers, tmp_path, "mb-1", domain, *args)
        assert _recovery(srv) == (1, _frames(journal / "journal-1.log"))  # its segment, its own record included
        assert _view(s) == before
    finally:
        stop_all(servers, c)
