"""A collaborating client in its own process (issue 11 tests and bench/service/bench_clients.py); run as a script.

Modes (first argument), each followed by the domain and a JSON argument; output is one JSON object per line.

``edit DOMAIN '{"session", "token", "steps", "seconds", "seed", "scene", "watch"}'``
    joins the session with the token (empty: opens it as its own and, with ``scene`` = a spacing, loads
    the demo scene sampled at it with the slab as zero and the sphere as one region; with ``one`` = a list
    of ids instead, its own tool moves just those: zero region = every other surfel), starts (unless
    ``watch`` is false: then ``final`` is not offered) a watcher on it from the
    state it fetched, prints ``{"ready": true, "client_id": ...}`` and waits for a line ``go`` on stdin.
    Then sends deform steps (small random translations) until ``steps`` were acknowledged or ``seconds``
    passed, prints ``{"client_id", "versions": [acknowledged versions, in order], "seconds"}`` and waits
    for a line ``final``: then compares its view (the fetched state with every model update its watcher
    received applied in version order) and its incremental ``state()`` with a fresh full GET_STATE and
    prints ``{"view_equal", "state_equal", "digest", "version", "watched": [versions], "authors": {version:
    author}}``. Exits on ``quit`` or end of input.
``hold DOMAIN '{"session", "token", "client_id", "points", "upload"}'``
    connects with the given client id, opens the session (empty token) or joins it, loads ``points``
    random surfels when ``points`` > 0, begins an upload and sends one chunk of ``upload`` surfels when
    ``upload`` > 0, prints ``{"ready": true, "version"}`` and sleeps until killed.
``resume DOMAIN '{"session", "client_id", "seconds"}'``
    connects with the given client id (retrying for up to ``seconds`` while the server does not answer
    it), joins the session (as a member, no token) and prints ``{"joined": true, "version", "surfels",
    "role"}`` or ``{"joined": false, "error": class name, "field"}``; a joined client then removes the
    surfel with the smallest id and prints ``{"changed": version}``. It exits without closing the session
    (the lease detaches it).
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from typing import Any, Dict, List

import numpy as np

import surfeledit
from surfeledit import errors
from surfeledit._protocol import proto
from surfeledit.results import Changes, State, merge


def emit(obj: Dict[str, Any]) -> None:
    print(json.dumps(obj), flush=True)


def digest(st: State) -> str:
    """A hash of the whole state (ids, positions, normals, radii, bit for bit)."""
    h = hashlib.sha256()
    for a in (st.ids, st.positions, st.normals, st.radii):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def apply(view: State, ev: surfeledit.UpdateEvent) -> State:
    """``view`` with one model update applied (a full update replaces it)."""
    if ev.full:
        return State(ev.version, ev.ids, ev.positions, ev.normals, ev.radii)
    return merge(view, Changes(version=ev.version, full=False, ids=ev.ids, positions=ev.positions, normals=ev.normals,
                               radii=ev.radii, removed=ev.removed))


def same(a: State, b: State) -> bool:
    return all(np.array_equal(getattr(a, n), getattr(b, n)) for n in ("ids", "positions", "normals", "radii"))


def watch(session: surfeledit.Session) -> surfeledit.Watcher:
    """A watcher of the session that the server greeted (its update writer matched the reader: updates are
    volatile, one published before the match is never seen); waits up to 20 s, where watch() waits 2 s."""
    w = session.watch()
    if not w.wait_greeted(20.0):
        raise SystemExit("the server did not greet the watcher within 20 s")
    return w


def fresh_state(session: surfeledit.Session) -> State:
    """The whole state by a full GET_STATE (not the session's incremental cache)."""
    ch = session._fetch(False, 0)
    return State(ch.version, ch.ids, ch.positions, ch.normals, ch.radii)


def _edit(domain: int, args: Dict[str, Any]) -> None:
    client = surfeledit.connect(domain=domain, spawn=False, timeout=20.0)
    token = str(args.get("token", ""))
    session = client.join_session(args["session"], token=token) if token else client.open_session(args["session"])
    if not token and args.get("scene"):
        from surfeledit.demo import default_scene
        pos, nrm, rad, part = default_scene(float(args["scene"]))
        session.load_points(pos, nrm, rad)
        ids = session.ids()
        session.set_regions(zero=ids[part == 0], one=ids[part == 1])
    elif args.get("one"):  # a tool of its own on these ids, rigid to the rest
        ids = session.ids()
        one = np.asarray(args["one"], dtype=ids.dtype)
        session.set_regions(zero=np.setdiff1d(ids, one), one=one)
    watcher = watch(session) if args.get("watch", True) else None
    view = fresh_state(session)  # after the watcher exists: no update is missed
    emit({"ready": True, "client_id": client.client_id})
    if sys.stdin.readline().strip() != "go":
        return
    rng = np.random.default_rng(int(args.get("seed", 0)))
    versions: List[int] = []
    t0 = time.perf_counter()
    while len(versions) < int(args["steps"]) and time.perf_counter() - t0 < float(args["seconds"]):
        step = session.deform(translation=tuple(rng.uniform(-1e-3, 1e-3, 3)))
        versions.append(step.version)
    emit({"client_id": client.client_id, "versions": versions, "seconds": time.perf_counter() - t0})
    for line in sys.stdin:
        if line.strip() != "final" or watcher is None:
            break
        truth = fresh_state(session)
        events = []
        deadline = time.monotonic() + 20.0
        while max([view.version] + [e.version for e in events]) < truth.version and time.monotonic() < deadline:
            ev = watcher.get(timeout=max(0.0, deadline - time.monotonic()))
            if ev is None:
                break
            events.append(ev)
        for ev in sorted(events, key=lambda e: e.version):
            if ev.version > view.version:
                view = apply(view, ev)
        emit({"view_equal": same(view, truth), "state_equal": same(session.state(), truth), "digest": digest(truth),
              "version": truth.version, "watched": [e.version for e in events],
              "authors": {str(e.version): e.author for e in events}})
    if watcher is not None:
        watcher.close()
    client.close()


def _hold(domain: int, args: Dict[str, Any]) -> None:
    client = surfeledit.connect(domain=domain, spawn=False, timeout=20.0, client_id=args["client_id"])
    token = str(args.get("token", ""))
    session = client.join_session(args["session"], token=token) if token else client.open_session(args["session"])
    points = int(args.get("points", 0))
    if points > 0:
        pos = np.random.default_rng(5).standard_normal((points, 3))
        session.load_points(pos, pos, np.full(points, 0.05))
    n = int(args.get("upload", 0))
    if n > 0:
        client.request(proto.Op.OP_LOAD_BEGIN, session.name, load_begin=proto.LoadBegin(total=10 * n, has_radii=True))
        pos = np.random.default_rng(3).standard_normal((n, 3))
        client.request(proto.Op.OP_LOAD_CHUNK, session.name, load_chunk=proto.LoadChunk(
            offset=0, positions=pos.ravel().tolist(), normals=pos.ravel().tolist(), radii=[0.01] * n))
    emit({"ready": True, "version": session.version})
    time.sleep(3600)


def _resume(domain: int, args: Dict[str, Any]) -> None:
    deadline = time.monotonic() + float(args.get("seconds", 20.0))
    while True:
        try:
            client = surfeledit.connect(domain=domain, spawn=False, timeout=2.0, client_id=args["client_id"])
            break
        except errors.ServerStartError:
            if time.monotonic() > deadline:
                raise
    try:
        session = client.join_session(args["session"])
    except errors.SurfelEditError as e:
        emit({"joined": False, "error": type(e).__name__, "field": e.field})
        os._exit(0)  # no CLOSE of anything: like a crash
    me = session.me()
    emit({"joined": True, "version": session.version, "surfels": int(session.info().surfels),
          "role": me.role if me else ""})
    session.remove(session.ids()[:1])
    emit({"changed": session.version})
    os._exit(0)  # leaves without closing: the server's lease detaches it


def main(argv: List[str]) -> None:
    mode, domain, arg = argv[1], int(argv[2]), json.loads(argv[3])
    {"edit": _edit, "hold": _hold, "resume": _resume}[mode](domain, arg)


if __name__ == "__main__":
    main(sys.argv)
