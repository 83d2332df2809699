"""The journal's writer thread (docs/journal.md "Snapshots: the writer thread"): the request loop saves the
state and starts a new segment; one writer thread writes, syncs and renames the snapshot file, and the
Snapshot record follows once the file is durable. Independent truth: a reference server without a journal
gets the same ops from clients with the same ids (test_journal_snapshot.Pair).

A snapshot file is held half-written without timing: the test puts a FIFO where the writer thread creates
the temporary file, so the writer blocks in open() until the test reads it. Steps must still be answered
then (the old blocking code stopped the request loop there), and a kill -9 in that state, or after a
failed write, or with a file renamed whose record never came, must recover exactly."""

from __future__ import annotations

import os
import shutil
import signal
import stat
import threading
import time
from pathlib import Path
from typing import List, Optional, Tuple

import surfeledit

from .conftest import ServerProcess, free_domain
from .test_journal_snapshot import Pair, _recovery, _restart, _server, _step, _view, settled, stop_all, wait_for

EVERY = 5  # --journal-snapshot-records


def _flags(journal: Path) -> Tuple[str, ...]:
    return ("--journal", str(journal), "--journal-snapshot-records", str(EVERY))


def _start(tmp_path: Path, hold: bool = False) -> Tuple[List[ServerProcess], Path, Pair, Optional[Path]]:
    """A reference server, a journaled one (snapshots every EVERY records) and the clients of both; with
    `hold`, a FIFO where the writer thread creates snapshot 1's temporary file: it blocks there until the
    FIFO is read."""
    ref_domain, j_domain = free_domain(), free_domain()
    journal = tmp_path / "journal"
    servers = [_server(tmp_path, "reference", ref_domain), _server(tmp_path, "journaled-0", j_domain, *_flags(journal))]
    fifo = journal / "snapshot-1.bin.tmp" if hold else None
    if fifo:
        os.mkfifo(fifo)
    return servers, journal, Pair(ref_domain, j_domain), fifo


def _open_until_snapshot_1_started(pair: Pair, srv: ServerProcess) -> None:
    pair.open_arms()  # more than EVERY records: snapshot 1 is taken and handed to the writer
    wait_for(lambda: "snapshot 1 started" in srv.log_tail(10**7), "snapshot 1 is started")


def _steps(pair: Pair, n: int, start: int = 0) -> None:
    for i in range(start, start + n):
        who, sign = ("alice", 1.0) if i % 2 == 0 else ("bob", -1.0)
        pair.both(who, lambda s: _step(s, (0.01 * sign, 0.0, 0.002 * (i % 3))))


def _recovered_view(domain: int) -> tuple:
    """The session as a new process of bob's sees it on the recovered server (its close then releases bob's
    tool: a new version; so only as a last look)."""
    c = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, client_id="bob-snap")
    try:
        return _view(c.join_session("snap"))
    finally:
        c.close()


def _records(segment: Path) -> List[Tuple[int, int]]:
    """(offset, kind) of every record of a log segment, from its framing (16-byte header; u32 length,
    u32 CRC, u8 kind, payload)."""
    data = segment.read_bytes()
    at, out = 16, []
    while at + 9 <= len(data):
        out.append((at, data[at + 8]))
        at += 9 + int.from_bytes(data[at:at + 4], "little")
    assert at == len(data)
    return out


def test_steps_are_answered_while_the_snapshot_file_is_held_and_kill9_then_recovers(tmp_path: Path) -> None:
    servers, journal, pair, fifo = _start(tmp_path, hold=True)  # the FIFO is never read here
    srv, j_domain = servers[-1], pair.domains[1]
    try:
        _open_until_snapshot_1_started(pair, srv)
        # The request loop goes on while the file is held half-way: these replies come back (the old code
        # waited in the loop for the file, i.e. forever here) ...
        _steps(pair, 2 * EVERY + 2)
        log = srv.log_tail(10**7)
        # ... while the file cannot have been written, and no second snapshot was started (one in flight).
        assert stat.S_ISFIFO(os.stat(fifo).st_mode) and "snapshot 1 taken" not in log
        assert "snapshot 2 started" not in log
        want = _view(pair.sessions["alice"][0])

        # kill -9 before the rename: no record, so nothing of snapshot 1 is used; the log is replayed.
        srv = _restart(servers, tmp_path, "journaled-1", j_domain, *_flags(journal))
        assert _recovery(srv)[0] == 0
        assert not list(journal.glob("*.tmp")), "a temporary snapshot file is removed at start"
        assert _view(pair.sessions["alice"][1]) == want
        # The same future, with snapshots taken again by the new process; then a kill -9 once more.
        _steps(pair, 2 * EVERY, start=100)
        assert settled(srv) >= 1
        want = _view(pair.sessions["bob"][0])
        srv = _restart(servers, tmp_path, "journaled-2", j_domain, *_flags(journal))
        assert _recovery(srv)[0] >= 2
        assert _view(pair.sessions["bob"][1]) == want
        _steps(pair, 2, start=200)
        final = [_view(s) for s in pair.sessions["alice"]]
        assert final[0] == final[1]
    finally:
        stop_all(servers, *pair.all())


def test_a_failed_snapshot_write_leaves_its_segment_to_the_log_and_the_next_one_is_taken(tmp_path: Path) -> None:
    servers, journal, pair, fifo = _start(tmp_path, hold=True)
    srv, j_domain = servers[-1], pair.domains[1]
    try:
        _open_until_snapshot_1_started(pair, srv)
        _steps(pair, 3)
        # Reading the FIFO to its end lets the writer write everything; its fdatasync then fails (a pipe):
        # the snapshot is not written, what it wrote is removed, segment 1 stays without a record.
        got = []
        reader = threading.Thread(target=lambda: got.append(len(fifo.read_bytes())))
        reader.start()
        reader.join(60.0)
        assert not reader.is_alive() and got[0] > 1000
        wait_for(lambda: "snapshot 1 not written" in srv.log_tail(10**7), "the failed write is reported")
        assert not fifo.exists() and not (journal / "snapshot-1.bin").exists()
        for i in range(4 * EVERY):  # until snapshot 2 is started (retried some records later), not beyond
            _steps(pair, 1, start=10 + i)
            if "snapshot 2 started" in srv.log_tail(10**7):
                break
        assert settled(srv) == 1 and "snapshot 2 taken" in srv.log_tail(10**7)
        want = _view(pair.sessions["alice"][0])
        srv = _restart(servers, tmp_path, "journaled-1", j_domain, *_flags(journal))
        assert _recovery(srv)[0] >= 2
        assert _view(pair.sessions["alice"][1]) == want
        # Without snapshot files the log from its start, through segment 1 (no record) and 2, recovers the same.
        copy = tmp_path / "journal-no-snapshots"
        shutil.copytree(journal, copy)
        for p in copy.glob("snapshot-*.bin"):
            p.unlink()
        assert (copy / "journal.log").exists(), "no snapshot before 2 was written: no segment was deleted"
        domain = free_domain()
        servers.append(_server(tmp_path, "fallback", domain, "--journal", str(copy)))
        assert _recovery(servers[-1])[0] == 0
        assert _recovered_view(domain) == want
    finally:
        stop_all(servers, *pair.all())


def test_a_snapshot_file_whose_record_never_came_is_ignored(tmp_path: Path) -> None:
    """kill -9 after the rename, before the record: made from a finished journal by cutting the newest
    segment that holds a Snapshot record at that record (dropping it, what follows and any later segment).
    The records cut are the last steps, so recovery must equal the reference as it was that many steps
    earlier, and must not restore the snapshot whose file is there but whose record is not."""
    servers, journal, pair, _ = _start(tmp_path)
    srv, j_domain = servers[-1], pair.domains[1]
    try:
        pair.open_arms()
        settled(srv)  # from here on every record is a step's (the views below are the reference's only)
        views = [_view(pair.sessions["alice"][0])]
        for i in range(3 * EVERY + 1):
            _steps(pair, 1, start=i)
            views.append(_view(pair.sessions["alice"][0]))
        assert settled(srv) >= 2
        srv.proc.kill()
        srv.proc.wait()

        segments = sorted(journal.glob("journal-*.log"), key=lambda p: int(p.stem.split("-")[1]))
        with_record = [p for p in segments if any(kind == 4 for _, kind in _records(p))]
        newest = with_record[-1]
        k = int(newest.stem.split("-")[1])
        assert (journal / f"snapshot-{k}.bin").exists()
        copy = tmp_path / "journal-cut"
        shutil.copytree(journal, copy)
        records = _records(newest)
        at = [i for i, (_, kind) in enumerate(records) if kind == 4][-1]
        cut = records[at + 1:]
        for p in segments[segments.index(newest) + 1:]:
            cut += _records(p)
            (copy / p.name).unlink()
        assert all(kind == 1 for _, kind in cut), "only steps follow the record"
        data = (copy / newest.name).read_bytes()
        (copy / newest.name).write_bytes(data[:records[at][0]])

        other = _server(tmp_path, "cut", j_domain, "--journal", str(copy))
        servers.append(other)
        restored = _recovery(other)[0]
        assert restored < k and f"snapshot {k} restored" not in other.log_tail(10**7)
        assert _recovered_view(j_domain) == views[len(views) - 1 - len(cut)]
    finally:
        stop_all(servers, *pair.all())


def test_sigterm_waits_for_the_snapshot_in_flight_then_stops_cleanly(tmp_path: Path) -> None:
    """A clean stop with a snapshot in flight: the server waits for the writer thread (held here until the test
    reads the FIFO; the write then fails, as a pipe cannot be synced), says so, exits 0, and the journal it
    leaves recovers the reference's state."""
    servers, journal, pair, fifo = _start(tmp_path, hold=True)
    srv, j_domain = servers[-1], pair.domains[1]
    try:
        _open_until_snapshot_1_started(pair, srv)
        _steps(pair, 3)
        want = _view(pair.sessions["alice"][0])
        srv.proc.send_signal(signal.SIGTERM)
        time.sleep(1.0)
        assert srv.alive, "the stop waits for the snapshot in flight"
        reader = threading.Thread(target=fifo.read_bytes)
        reader.start()
        reader.join(60.0)
        assert srv.proc.wait(timeout=60) == 0
        log = srv.log_tail(10**7)
        assert "snapshot 1 not written" in log and "stopped" in log
        srv = _server(tmp_path, "journaled-1", j_domain, *_flags(journal))
        servers.append(srv)
        assert _recovery(srv)[0] == 0
        assert _view(pair.sessions["alice"][1]) == want
    finally:
        stop_all(servers, *pair.all())
