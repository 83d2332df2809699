"""A second DDS participant in its own process, for identity and lease tests (run as a script).

Modes (first argument), each followed by the domain and a JSON argument:

``spoof DOMAIN '[{"client_id": ..., "request_id": ..., "session": ..., "op": "OP_DEFORM"}, ...]'``
    writes raw ``Request`` samples (a deform of (0.5, 0, 0) for ``OP_DEFORM``) from a fresh writer,
    waits until the server acknowledged them, then counts for ``listen_s`` seconds the replies that
    carry the spoofed ids, read in the victim's own reply partition, and prints ``{"replies": n}``.
``forge DOMAIN '{"client_id": ..., "request_id": ..., "request_op": N}'``
    writes one forged OK ``Reply`` in the victim's reply partition (visible in discovery), waits
    until every matched reader acknowledged it, prints ``{"written": 1}``.
``listen DOMAIN '{"seconds": s}'``
    reads the reply topic in the default partition, prints ``{"ready": true}``, then after ``s``
    seconds ``{"replies": n}``.
``upload DOMAIN '{"session": ..., "token": ..., "total": T, "chunks": k, "chunk": n}'``
    connects with the real client, joins the session with the token, begins an upload of ``T``
    surfels and sends ``k`` chunks of ``n``, prints ``{"ready": true}`` and sleeps until killed.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any, Dict, List

from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter, Publisher
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader, Subscriber
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from surfeledit._protocol import TOPIC_REPLY, TOPIC_REQUEST, proto, reply_qos, request_qos
from surfeledit._protocol import reply_partition, reply_reader_qos
from surfeledit.connection import wait_matched


def _in_partition(name: str) -> Qos:
    return Qos(Policy.Partition(partitions=[name]))


def _spoof(domain: int, requests: List[Dict[str, Any]], listen_s: float = 1.0) -> Dict[str, int]:
    dp = DomainParticipant(domain)
    writer = DataWriter(dp, Topic(dp, TOPIC_REQUEST, proto.Request), qos=request_qos())
    victim = requests[0]["client_id"]
    reader = DataReader(Subscriber(dp, qos=_in_partition(reply_partition(victim))),
                        Topic(dp, TOPIC_REPLY, proto.Reply), qos=reply_qos())
    if not wait_matched(dp, (writer, reader), 10.0):
        raise SystemExit("no server matched")
    spoofed = {(r["client_id"], int(r["request_id"])) for r in requests}
    for r in requests:
        req = proto.Request(client_id=r["client_id"], request_id=int(r["request_id"]), session=r["session"],
                            op=proto.Op[r["op"]])
        if r["op"] == "OP_DEFORM":
            req.deform = [proto.Deform(translation=proto.Vec3(x=0.5, y=0.0, z=0.0), axis=proto.Vec3(x=0.0, y=0.0, z=1.0),
                                       blend="smooth")]
        writer.write(req)
    writer.wait_for_acks(duration(seconds=10))
    replies = 0
    deadline = time.monotonic() + listen_s
    while time.monotonic() < deadline:
        for s in reader.take(N=64):
            if isinstance(s, proto.Reply) and (s.client_id, int(s.request_id)) in spoofed:
                replies += 1
        time.sleep(0.02)
    return {"replies": replies}


def _forge(domain: int, args: Dict[str, Any]) -> Dict[str, int]:
    dp = DomainParticipant(domain)
    writer = DataWriter(Publisher(dp, qos=_in_partition(reply_partition(args["client_id"]))),
                        Topic(dp, TOPIC_REPLY, proto.Reply), qos=reply_reader_qos())  # what the victim reads
    if not wait_matched(dp, (writer,), 10.0):
        raise SystemExit("no reply reader matched")
    time.sleep(0.3)  # let every reader of the topic match, not only the first
    writer.write(proto.Reply(client_id=args["client_id"], request_id=int(args["request_id"]),
                             status=proto.Status.STATUS_OK, request_op=int(args["request_op"])))
    writer.wait_for_acks(duration(seconds=10))
    return {"written": 1}


def _listen(domain: int, args: Dict[str, Any]) -> Dict[str, int]:
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, TOPIC_REPLY, proto.Reply), qos=reply_qos())
    print(json.dumps({"ready": True}), flush=True)
    replies = 0
    deadline = time.monotonic() + float(args["seconds"])
    while time.monotonic() < deadline:
        replies += sum(isinstance(s, proto.Reply) for s in reader.take(N=64))
        time.sleep(0.02)
    return {"replies": replies}


def _upload(domain: int, args: Dict[str, Any]) -> None:
    import numpy as np

    import surfeledit
    client = surfeledit.connect(domain=domain, spawn=False, timeout=10.0)
    session = client.join_session(args["session"], token=args["token"])
    n, total = int(args["chunk"]), int(args["total"])
    client.request(proto.Op.OP_LOAD_BEGIN, session.name, load_begin=proto.LoadBegin(total=total, has_radii=True))
    rng = np.random.default_rng(7)
    for k in range(int(args["chunks"])):
        pos = rng.standard_normal((n, 3))
        client.request(proto.Op.OP_LOAD_CHUNK, session.name, load_chunk=proto.LoadChunk(
            offset=k * n, positions=pos.ravel().tolist(), normals=pos.ravel().tolist(), radii=[0.01] * n))
    print(json.dumps({"ready": True}), flush=True)
    time.sleep(3600)


def main(argv: List[str]) -> None:
    mode, domain, arg = argv[1], int(argv[2]), json.loads(argv[3])
    if mode == "spoof":
        print(json.dumps(_spoof(domain, arg)), flush=True)
    elif mode == "forge":
        print(json.dumps(_forge(domain, arg)), flush=True)
    elif mode == "listen":
        print(json.dumps(_listen(domain, arg)), flush=True)
    elif mode == "upload":
        _upload(domain, arg)
    else:
        raise SystemExit(f"unknown mode {mode!r}")


if __name__ == "__main__":
    main(sys.argv)
