"""The journal's contract beyond kill -9 (PROTOCOL.md "Journal"): replies of request ids survive a
restart (accepted and refused ones: a repeat is answered, never re-applied), invitation tokens and
roles survive, a clean stop with group commit keeps the last group, and a journal directory that
cannot be used stops the server with exit code 3."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit._protocol import proto
from surfeledit.local import LocalSession

from .conftest import ServerProcess, free_domain, generated_scene, server_executable

JOURNAL_EXIT = 3


def _server(tmp_path: Path, domain: int, journal: Path, n: int, *extra: str) -> ServerProcess:
    srv = ServerProcess(server_executable(), domain, tmp_path / f"server-{n}.log",
                        extra=("--journal", str(journal), "--threads", "1") + extra)
    srv.wait_ready(20.0)
    return srv


def _exit_code(srv: ServerProcess, timeout: float = 20.0) -> int:
    try:
        return srv.proc.wait(timeout=timeout)
    finally:
        srv.stop()


@pytest.mark.parametrize("sync", [("--journal-sync", "op"), ("--journal-sync", "group", "--journal-group-ms", "20")])
def test_replies_tokens_and_state_survive_a_restart(tmp_path: Path, sync: Tuple[str, ...]) -> None:
    domain = free_domain()
    journal = tmp_path / "journal"
    positions, normals, radii, part = generated_scene(0.1)
    ids = np.arange(len(positions), dtype=np.uint64)
    srv = _server(tmp_path, domain, journal, 0, *sync)
    owner_client = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, reconnect=20.0)
    other = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, reconnect=20.0)
    try:
        s = owner_client.open_session("kept")
        s.load_points(positions, normals, radii)
        s.set_regions(zero=ids[part == 0], one=ids[part == 1])
        token = s.invite("editor")
        step = owner_client.new_request(proto.Op.OP_DEFORM, "kept",
                                        deform=proto.Deform(translation=proto.Vec3(0.0, 0.0, 0.01),
                                                            axis=proto.Vec3(0.0, 0.0, 1.0), blend="smooth"))
        first = owner_client.call(step)
        bad = owner_client.new_request(proto.Op.OP_REMOVE, "kept", remove=proto.Remove(ids=[10**9]))
        refused = owner_client.call(bad, check=False)
        assert refused.status != proto.Status.STATUS_OK
        history = [(h.version, h.op, h.client) for h in s.history()]
        info = s.info()

        srv.stop()  # SIGTERM: a clean stop writes the last group's replies first
        srv = _server(tmp_path, domain, journal, 1, *sync)
        log = srv.log_tail(10**6)
        assert "recovered" in log and "request(s)" in log

        # A repeat of an accepted request id gets its stored reply: same version, applied once.
        again = owner_client.call(step)
        assert again.status == proto.Status.STATUS_OK and again.version == first.version
        # A repeat of a refused request id gets the same refusal, not a fresh evaluation.
        refused_again = owner_client.call(bad, check=False)
        assert (refused_again.status, refused_again.field, refused_again.message) == \
            (refused.status, refused.field, refused.message)
        assert refused_again.version == refused.version
        # The session, its history (versions, ops, authors) and state hash are back.
        assert [(h.version, h.op, h.client) for h in s.history()] == history
        assert s.info().state_hash == info.state_hash
        # The invitation made before the restart still admits (the replayed token is the same).
        joined = other.join_session("kept", token=token)
        joined.remove(ids[part == 0][:1])  # a slab surfel: outside the owner's lock (its tool moves the sphere)
        s.info()
        assert s.version == first.version + 1

        # An independent replay in this process reaches the same state.
        local = LocalSession("replay", threads=1)
        local.load_points(positions, normals, radii)
        local.set_regions(zero=ids[part == 0], one=ids[part == 1])
        local.deform(translation=(0.0, 0.0, 0.01))
        local.remove(ids[part == 0][:1])
        assert int(local.core.state_hash) == int(s.info().state_hash)
    finally:
        for c in (owner_client, other):
            c.reconnect = 0.0
        srv.stop()
        owner_client.close()
        other.close()


def test_unusable_journal_directory_exits_with_code_3(tmp_path: Path) -> None:
    exe = server_executable()
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory")
    srv = ServerProcess(exe, free_domain(), tmp_path / "bad.log", extra=("--journal", str(blocker / "j")))
    assert _exit_code(srv) == JOURNAL_EXIT
    assert "journal" in srv.log_tail()

    not_a_journal = tmp_path / "other"
    not_a_journal.mkdir()
    (not_a_journal / "journal.log").write_bytes(b"\x00" * 64)
    srv = ServerProcess(exe, free_domain(), tmp_path / "magic.log", extra=("--journal", str(not_a_journal)))
    assert _exit_code(srv) == JOURNAL_EXIT
    assert "not a surfeledit journal" in srv.log_tail()


@pytest.mark.parametrize("record_format", [0, 7])
def test_journal_of_another_record_format_is_refused(tmp_path: Path, record_format: int) -> None:
    """The header's record format (PROTOCOL.md "Journal"): a journal written before it was recorded (0)
    or by a later server (7) is refused with a message naming both formats, never replayed."""
    journal = tmp_path / "j"
    journal.mkdir()
    header = b"SEJOURNL" + (1).to_bytes(4, "little") + record_format.to_bytes(4, "little") + bytes(4)
    (journal / "journal.log").write_bytes(header)
    srv = ServerProcess(server_executable(), free_domain(), tmp_path / "fmt.log", extra=("--journal", str(journal)))
    assert _exit_code(srv) == JOURNAL_EXIT
    tail = srv.log_tail()
    assert f"records of format {record_format}" in tail and "reads record formats 1 to 2" in tail
    assert (journal / "journal.log").read_bytes() == header  # left as it was


def test_second_server_on_the_same_journal_is_refused(tmp_path: Path) -> None:
    journal = tmp_path / "journal"
    first = _server(tmp_path, free_domain(), journal, 0)
    try:
        second = ServerProcess(server_executable(), free_domain(), tmp_path / "second.log",
                               extra=("--journal", str(journal)))
        assert _exit_code(second) == JOURNAL_EXIT
        assert "in use by another server" in second.log_tail()
        assert first.alive
    finally:
        first.stop()


def test_torn_tail_is_cut_and_the_rest_recovered(tmp_path: Path) -> None:
    """Bytes of a half-written record after the last intact one: cut with a log line, the sessions
    before it recovered."""
    domain = free_domain()
    journal = tmp_path / "journal"
    srv = _server(tmp_path, domain, journal, 0)
    client = surfeledit.connect(domain=domain, spawn=False, timeout=10.0)
    try:
        s = client.open_session("torn")
        positions, normals, radii, _ = generated_scene(0.1)
        s.load_points(positions, normals, radii)
        want = int(s.info().state_hash)
        srv.proc.kill()
        srv.proc.wait()
        with open(journal / "journal.log", "ab") as f:
            f.write(b"\x40\x00\x00\x00\x12\x34\x56\x78\x01half a record")
        srv = _server(tmp_path, domain, journal, 1)
        assert "torn or corrupt tail" in srv.log_tail(10**6)
        client.reconnect = 20.0
        time.sleep(0.1)
        assert int(s.info().state_hash) == want
    finally:
        client.reconnect = 0.0
        srv.stop()
        client.close()


def test_recovered_client_that_never_returns_is_detached_by_its_lease(tmp_path: Path) -> None:
    """After a restart the recovered clients are bound to no writer: each one's lease (the rejoin
    time) runs until its first request. One that comes back keeps its place; one that never does is
    detached."""
    domain = free_domain()
    journal = tmp_path / "journal"
    lease = ("--client-lease-ms", "600", "--journal-rejoin-ms", "4000")
    srv = _server(tmp_path, domain, journal, 0, *lease)
    back = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, reconnect=20.0)
    silent = surfeledit.connect(domain=domain, spawn=False, timeout=10.0)
    try:
        s = back.open_session("leased")
        silent.join_session("leased", token=s.invite("viewer"))
        assert int(s.info().clients) == 2
        srv.proc.kill()
        srv.proc.wait()
        srv = _server(tmp_path, domain, journal, 1, *lease)
        assert int(s.info().clients) == 2  # both recovered; `back` is bound again by this request
        deadline = time.monotonic() + 15.0
        while int(s.info().clients) != 1 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert int(s.info().clients) == 1
        assert f"client {silent.client_id} detached" in srv.log_tail(10**6)
        time.sleep(1.0)  # `back` keeps sending: its lease stopped at its first request
        assert int(s.info().clients) == 1
    finally:
        back.reconnect = 0.0
        srv.stop()
        back.close()
        silent.close()


def test_load_file_is_replayed_from_the_file_and_a_changed_file_stops_recovery(tmp_path: Path) -> None:
    """OP_LOAD_FILE is journaled when its load commits, with the model's state hash: recovery reads the
    file again (the deferred path) and checks the hash; a file changed since refuses to start (exit 3)."""
    from .test_hardening_files import save_cloud

    domain = free_domain()
    journal = tmp_path / "journal"
    root = tmp_path / "data"
    root.mkdir()
    save_cloud(root / "cloud.ply", n=300, seed=5)
    exe = server_executable()

    def start(n: int) -> ServerProcess:
        srv = ServerProcess(exe, domain, tmp_path / f"file-{n}.log", data_root=root,
                            extra=("--journal", str(journal), "--threads", "1"))
        return srv

    srv = start(0)
    srv.wait_ready(20.0)
    client = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, reconnect=20.0)
    try:
        s = client.open_session("from-file")
        assert s.load_file("cloud.ply").surfels == 300
        s.remove([0, 1, 2])
        want = int(s.info().state_hash)
        srv.proc.kill()
        srv.proc.wait()
        srv = start(1)
        srv.wait_ready(20.0)
        assert int(s.info().state_hash) == want
        assert [h.op for h in s.history()] == ["load", "remove"]
        srv.stop()

        save_cloud(root / "cloud.ply", n=300, seed=6)  # same size, other points
        bad = start(2)
        assert _exit_code(bad) == JOURNAL_EXIT
        assert "OP_LOAD_FILE" in bad.log_tail() and "changed" in bad.log_tail()
    finally:
        client.reconnect = 0.0
        srv.stop()
        client.close()


def test_a_process_reusing_its_client_id_never_meets_its_predecessors_replies(tmp_path: Path) -> None:
    """A client process and the server both crash; a new process takes the same client id (to find its
    sessions again). The recovered reply store still holds its predecessor's replies by request id, so the
    new process's request ids must not repeat the old ones (PROTOCOL.md "Idempotence"): its requests are
    applied, not refused as repeats with another op nor answered with an old reply."""
    domain = free_domain()
    journal = tmp_path / "journal"
    srv = _server(tmp_path, domain, journal, 0)
    old = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, client_id="reused")
    try:
        positions, normals, radii, _ = generated_scene(0.1)
        s = old.open_session("reused")
        s.load_points(positions, normals, radii)
        s.remove(np.arange(3))
        info = s.info()
        before = (int(info.surfels), int(info.state_hash))
        srv.proc.kill()
        srv.proc.wait()
        old.close()
        srv = _server(tmp_path, domain, journal, 1)
        with surfeledit.connect(domain=domain, spawn=False, timeout=10.0, client_id="reused") as new:
            t = new.join_session("reused")
            info = t.info()
            assert (int(info.surfels), int(info.state_hash)) == before
            t.remove(np.arange(3, 5))
            assert int(t.info().surfels) == len(positions) - 5
    finally:
        srv.stop()
