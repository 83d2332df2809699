"""Identity and access against a real server: client ids bound to their DDS writer, private sessions,
invitations and roles. Spoofing and forging run in a second participant in its own process
(peer_process.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any, Callable, Dict, Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit import errors
from surfeledit._protocol import proto

from .conftest import ServerProcess, generated_scene

PEER = Path(__file__).with_name("peer_process.py")


def run_peer(mode: str, domain: int, arg: Any, timeout: float = 30.0) -> Dict[str, Any]:
    """Runs peer_process.py in a new process and returns the JSON it printed last."""
    env = dict(os.environ)
    out = subprocess.run([sys.executable, str(PEER), mode, str(domain), json.dumps(arg)], capture_output=True,
                         text=True, timeout=timeout, env=env, check=False)
    assert out.returncode == 0, f"peer {mode} failed ({out.returncode}):\n{out.stdout}\n{out.stderr}"
    return json.loads(out.stdout.strip().splitlines()[-1])


def loaded_session(client: surfeledit.Client, name: str) -> surfeledit.Session:
    positions, normals, radii, part = generated_scene()
    s = client.open_session(name)
    s.load_points(positions, normals, radii)
    s.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero(part == 1))
    return s


def snapshot(s: surfeledit.Session) -> Tuple[int, int, int]:
    info = s.info()
    return int(s.version), int(info.state_hash), int(info.clients)


def test_requests_with_a_spoofed_client_id_are_refused_without_a_reply(
        server: ServerProcess, client: surfeledit.Client) -> None:
    s = loaded_session(client, "victim")
    first = s.deform(translation=(0.0, 0.0, -0.01))
    before = snapshot(s)
    next_id = client._next_id  # the id the victim's next request will carry
    spoofs = [dict(client_id=client.client_id, request_id=next_id + 5, session="victim", op="OP_DEFORM"),
              dict(client_id=client.client_id, request_id=next_id + 6, session="victim", op="OP_CLOSE_SESSION"),
              # Pre-filling the victim's next request id: must not become the answer to its deform.
              dict(client_id=client.client_id, request_id=next_id + 1, session="victim", op="OP_INFO")]
    assert run_peer("spoof", server.domain, spoofs)["replies"] == 0
    assert snapshot(s) == before  # (request id next_id) nothing applied, still attached, same hash
    assert client._next_id == next_id + 1
    step = s.deform(translation=(0.0, 0.0, -0.01))  # request id next_id + 1: the spoofed INFO's id
    assert step.seq == first.seq + 1 and step.version == before[0] + 1 and step.moved > 0
    assert "refused without a reply" in server.log_tail(20000)


def test_a_forged_reply_makes_the_client_raise_never_return_a_default(
        server: ServerProcess, client: surfeledit.Client) -> None:
    s = loaded_session(client, "forged")
    run_peer("forge", server.domain, dict(client_id=client.client_id, request_id=client._next_id,
                                          request_op=int(proto.Op.OP_INFO.value)))
    with pytest.raises(errors.ReplyMismatchError):
        s.deform(translation=(0.0, 0.0, -0.01))
    # Same op, but no step result: still refused.
    run_peer("forge", server.domain, dict(client_id=client.client_id, request_id=client._next_id,
                                          request_op=int(proto.Op.OP_DEFORM.value)))
    with pytest.raises(errors.ReplyMismatchError):
        s.deform(translation=(0.0, 0.0, -0.01))


def _refusal(call: Callable[[], Any]) -> Tuple[type, str, str]:
    with pytest.raises(errors.SurfelEditError) as info:
        call()
    e = info.value
    return type(e), e.field, e.message


def test_private_sessions_need_a_token_and_refuse_like_a_missing_session(
        make_client: Callable[[], surfeledit.Client]) -> None:
    owner, other = make_client(), make_client()
    s = loaded_session(owner, "private")
    missing = _refusal(lambda: other.join_session("absent"))
    assert missing[0] is errors.NotFoundError and missing[1] == "session"
    for token in ("", "0" * 32, "not-a-token"):
        kind, field, message = _refusal(lambda: other.join_session("private", token=token))
        assert (kind, field, message.replace("private", "absent")) == missing
    # Listing and info show nothing of it to a non-member.
    assert "private" not in other.info().sessions and "private" in owner.info().sessions
    reply = other.request(proto.Op.OP_INFO, "private")
    assert not reply.session_info and reply.version == 0
    # Not a member: no op on it, and its name cannot be opened over it.
    with pytest.raises(errors.ConflictError):
        other.request(proto.Op.OP_DEFORM, "private", deform=proto.Deform(blend="smooth"))
    refused = other.request(proto.Op.OP_DEFORM, "private", check=False, deform=proto.Deform(blend="smooth"))
    assert refused.version == 0  # the session's version is not revealed either
    with pytest.raises(errors.ConflictError):
        other.open_session("private")
    assert s.info().clients == 1
    # With an editor token: joined, listed, and it may edit.
    editor = other.join_session("private", token=s.invite("editor"))
    assert "private" in other.info().sessions and s.info().clients == 2
    # Its own tool (issue 11): the owner releases the sphere, the editor takes it.
    assert s.release()
    positions, normals, radii, part = generated_scene()
    editor.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero(part == 1))
    step = editor.deform(translation=(0.0, 0.0, -0.01))
    assert step.moved > 0
    assert s.history()[-1].client == other.client_id
    # Only the owner invites.
    with pytest.raises(errors.PermissionDeniedError):
        editor.invite("viewer")


def test_a_viewer_reads_but_every_change_is_refused_and_changes_nothing(
        make_client: Callable[[], surfeledit.Client]) -> None:
    owner, other = make_client(), make_client()
    s = loaded_session(owner, "shown")
    s.deform(translation=(0.0, 0.0, -0.01))
    viewer = other.join_session("shown", token=s.invite("viewer"))
    before = snapshot(s)
    positions, normals, radii, part = generated_scene()
    mutations = {
        "load_points": lambda: viewer.load_points(positions, normals, radii),
        "load_begin": lambda: other.request(proto.Op.OP_LOAD_BEGIN, "shown",
                                            load_begin=proto.LoadBegin(total=10, has_radii=True)),
        "set_regions": lambda: viewer.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero(part == 1)),
        "deform": lambda: viewer.deform(translation=(0.0, 0.0, -0.01)),
        "configure": lambda: viewer.configure(algorithm="none"),
        "remove": lambda: viewer.remove(np.array([0], dtype=np.uint64)),
        "undo": viewer.undo,
        "redo": viewer.redo,
        "merge": viewer.merge,
        "invite": lambda: viewer.invite("editor"),
    }
    for name, call in mutations.items():
        with pytest.raises(errors.PermissionDeniedError) as info:
            call()
        assert info.value.status == 7 and info.value.field == "session", name
        assert snapshot(s) == before, name
    # Reading works and sees the owner's state.
    np.testing.assert_array_equal(viewer.positions(), s.positions())
    assert [h.version for h in viewer.history()] == [h.version for h in s.history()]
    assert viewer.info().state_hash == before[1]


def test_replies_travel_in_the_client_partition_not_the_default_one(
        server: ServerProcess, client: surfeledit.Client) -> None:
    """Reduces accidental exposure only (any participant may join a partition; PROTOCOL.md)."""
    listener = subprocess.Popen([sys.executable, str(PEER), "listen", str(server.domain), json.dumps({"seconds": 3})],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert json.loads(listener.stdout.readline() or "{}").get("ready") if listener.stdout else False
        s = loaded_session(client, "quiet")
        for _ in range(3):
            s.deform(translation=(0.0, 0.0, -0.01))
        out, err = listener.communicate(timeout=30)
    finally:
        if listener.poll() is None:
            listener.kill()
            listener.wait()
    assert listener.returncode == 0, err
    assert json.loads(out.strip().splitlines()[-1])["replies"] == 0
