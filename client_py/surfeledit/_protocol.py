"""Topic names, partitions, QoS and the generated topic types (``proto``) of the surfeledit protocol.

``proto`` is the module ``surfeledit._proto`` generated from ``proto/surfeledit.idl`` by
``proto/idl2py.py`` (the CMake build writes it). When it is missing (a source checkout that was not
built yet) it is generated in memory from the repository's IDL, so the client still works.
"""

from __future__ import annotations

import importlib.util
import logging
import sys
import types
from pathlib import Path

from cyclonedds.qos import Policy, Qos
from cyclonedds.util import duration

from . import wire_arrays

__all__ = ["proto", "TOPIC_REQUEST", "TOPIC_REPLY", "TOPIC_UPDATE", "request_qos", "reply_qos", "update_qos",
           "request_writer_qos", "reply_reader_qos", "request_partition", "reply_partition",
           "COMPACT_UPDATE_PARTITION", "CLIENT_LIVELINESS_S", "REPO_ROOT"]

_log = logging.getLogger("surfeledit")

TOPIC_REQUEST = "surfeledit_request"
TOPIC_REPLY = "surfeledit_reply"
TOPIC_UPDATE = "surfeledit_update"

#: Repository root when running from a source checkout (client_py/surfeledit/_protocol.py -> ../..).
REPO_ROOT = Path(__file__).resolve().parents[2]


def _qos() -> Qos:
    # PROTOCOL.md: reliable (max blocking 10 s), keep-all, volatile, for all three topics.
    return Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=10)),
               Policy.History.KeepAll,
               Policy.Durability.Volatile)


def request_qos() -> Qos:
    return _qos()


def reply_qos() -> Qos:
    return _qos()


def update_qos() -> Qos:
    return _qos()


# Liveliness lease the request writer offers (automatic: Cyclone asserts it while the process
# lives); the server detaches a client whose writer is gone for its --client-lease-ms after that.
CLIENT_LIVELINESS_S = 1.0


def request_partition(user: str) -> str:
    """The partition a secured client of ``user`` writes its requests in (PROTOCOL.md, "Security"):
    only that identity may write there, so the server reads it as the authenticated user."""
    return "surfeledit.req." + user


def reply_partition(client_id: str) -> str:
    """The partition the server writes a client's replies in (PROTOCOL.md, "Identity and access")."""
    return "surfeledit.reply." + client_id


# The partition the server writes the compact encoding of updates in (PROTOCOL.md, "Updates, compact").
COMPACT_UPDATE_PARTITION = "surfeledit.update.compact"


def reply_reader_qos() -> Qos:
    """The protocol's reply QoS, transient-local: the server's per-client reply writer is made at the
    first reply, and the reply written before this reader matched it still arrives."""
    return Qos(*[p for p in reply_qos().policies if not isinstance(p, type(Policy.Durability.Volatile))],
               Policy.Durability.TransientLocal)


def request_writer_qos() -> Qos:
    """The protocol's request QoS plus automatic liveliness (PROTOCOL.md, "Leases")."""
    return Qos(*request_qos().policies, Policy.Liveliness.Automatic(duration(seconds=CLIENT_LIVELINESS_S)))


def _generate_in_memory() -> types.ModuleType:
    """Builds ``surfeledit._proto`` from ``<repo>/proto/surfeledit.idl`` with ``<repo>/proto/idl2py.py``."""
    gen = REPO_ROOT / "proto" / "idl2py.py"
    idl = REPO_ROOT / "proto" / "surfeledit.idl"
    if not gen.is_file() or not idl.is_file():
        raise ImportError("surfeledit._proto is missing: build the project (cmake) or run "
                          "'python proto/idl2py.py proto/surfeledit.idl -o client_py/surfeledit/_proto.py'")
    spec = importlib.util.spec_from_file_location("_surfeledit_idl2py", gen)
    assert spec is not None and spec.loader is not None
    idl2py = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = idl2py  # dataclasses look their module up in sys.modules
    spec.loader.exec_module(idl2py)
    source = idl2py.generate_file(idl)
    module = types.ModuleType("surfeledit._proto")
    module.__file__ = str(Path(__file__).with_name("_proto.py"))
    # cyclonedds resolves member types through sys.modules[cls.__module__]; register before executing.
    sys.modules["surfeledit._proto"] = module
    exec(compile(source, "<surfeledit._proto>", "exec", dont_inherit=True), module.__dict__)
    _log.info("surfeledit._proto not built; generated it in memory from %s", idl)
    return module


try:
    from . import _proto as proto
except ImportError:  # pragma: no cover - depends on whether the build ran
    proto = _generate_in_memory()

# The surfels' geometry of updates and state pages (nested in replies) arrives as numpy arrays, and uploads' chunks
# are sent from arrays (wire_arrays.py).
wire_arrays.install([proto.Update, proto.StatePage, proto.LoadChunk])
