"""The connection to a server: :class:`Client` (request/reply over Cyclone DDS) and :func:`connect`.

A request is written on ``surfeledit_request`` and its reply is the ``surfeledit_reply`` sample with
the same client id and request id (PROTOCOL.md). Sessions (:mod:`surfeledit.session`) and watchers
(:mod:`surfeledit.watcher`) attach themselves to the client that made them; closing the client closes
them. Times are seconds unless a name says ``_ms``.
"""

from __future__ import annotations

import logging
import os
import socket
import subprocess
import threading
import time
import uuid
from pathlib import Path
from typing import Any, List, Optional, Union

from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter, Publisher
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import Subscriber
from cyclonedds.topic import Topic

from . import errors
from ._protocol import (COMPACT_UPDATE_PARTITION, TOPIC_REPLY, TOPIC_REQUEST, TOPIC_UPDATE, proto, reply_partition,
                        reply_reader_qos, request_partition, request_writer_qos, update_qos)
from .arrays import as_int
from .dds_status import alive_writers, publication_matched
from .inbox import Inbox, _delete, _matched, wait_matched
from .reconnect import await_reply_across_restart
from .security import (SecurityConfig, access_checked, claim_identity, participant_qos, release_identity,
                       security_config)
from .server_process import DOMAIN_TAKEN_EXIT_CODE, exit_message, server_ready, spawn_server, stop_process
from .session import Session

__all__ = ["Client", "connect", "Inbox"]

_log = logging.getLogger("surfeledit")

_PROBE_S = 1.5  # how long connect() looks for an already running server before spawning one
_WATCH_MATCH_S = 2.0  # how long a new update reader waits for the server's update writer
_GONE_POLL_S = 0.1  # how often a waiting request checks that the server's reply writer is alive
_GONE_GRACE_S = 0.3  # how long it may be not alive before the server counts as gone


def _op_label(op: int) -> str:
    """The name of an op number for messages ("OP_DEFORM"), or "op 99" for a number outside proto.Op."""
    try:
        return proto.Op(int(op)).name
    except ValueError:
        return f"op {int(op)}"


class Client:
    """A connection to a surfeledit server on one DDS domain (use :func:`connect`).

    Thread-safe for requests (one request is in flight at a time). Close it (or use ``with``) to
    close its sessions and watchers, release the DDS entities and stop a server it spawned.
    ``reconnect`` (seconds, default 0): re-send a request whose server is gone until a restarted server
    (``--journal``) answers it (:mod:`surfeledit.reconnect`).
    """

    def __init__(self, domain: int, timeout: float = 10.0, _server: Optional[subprocess.Popen] = None,
                 reconnect: float = 0.0, client_id: Optional[str] = None,
                 security: Optional[Union[str, "os.PathLike[str]", SecurityConfig]] = None) -> None:
        # The server's --domain range (Cyclone's port mapping; -1 would mean "the configured default" to DDS).
        self.domain = as_int(domain, "domain", 0, 233)
        self.timeout = float(timeout)
        # > 0: a request whose server is gone is re-sent (same id) for this many seconds (reconnect.py)
        self.reconnect = float(reconnect)
        if client_id is not None and (not isinstance(client_id, str) or not client_id or len(client_id) > 256):
            raise errors.InvalidArgumentError(f"client_id {client_id!r}: expected 1..256 characters", "client_id")
        # A fresh id, or the caller's: a restarted process reusing its id finds its sessions again once
        # the server detached the old process (its lease) and within the grace period (PROTOCOL.md).
        # DDS Security (security.py): the participant authenticates with this identity; its client id
        # starts with "<user>." (the reply partition its permissions let it read).
        self.security = security_config(security)
        prefix = self.security.client_id_prefix() if self.security else ""
        self.client_id = client_id or f"{prefix}{socket.gethostname()}-{os.getpid()}-{uuid.uuid4().hex[:12]}"
        # Request ids start at this process's creation time in microseconds since the epoch: a restarted
        # process reusing its client id never repeats an id of its previous life, whose replies the server
        # may still hold (its reply store, restored by --journal) or still deliver (the reply writer's
        # transient-local history), so an old reply is never taken for a new request.
        self._next_id = time.time_ns() // 1000
        self._lock = threading.RLock()
        self._server = _server
        self._server_log: Optional[Path] = None
        self._server_info: Optional["proto.ServerInfo"] = None
        self._closed = False
        self._children: List[Any] = []  # sessions and watchers, closed with the client

        self._participant = self._req_topic = self._rep_topic = self._writer = self._rep_sub = self._req_pub = None
        self._upd_topic: Optional[Topic] = None
        self._replies: Optional[Inbox] = None
        self._server_seen = False  # a reply writer was alive once: losing it then means the server is gone
        claim_identity(self.security)  # one identity per process (security.py)
        try:
            self._make_entities()
        except BaseException:
            self.close()
            raise

    def _make_entities(self) -> None:
        with access_checked(self.security, "participant"):
            self._participant = DomainParticipant(self.domain, qos=participant_qos(self.security))
        with access_checked(self.security, "request topic"):
            self._req_topic = Topic(self._participant, TOPIC_REQUEST, proto.Request)
            self._rep_topic = Topic(self._participant, TOPIC_REPLY, proto.Reply)
        with access_checked(self.security, "request writer"):
            # With a user: requests in its own partition, which names it to the server (--grant roles).
            if self.security is not None and self.security.user:
                self._req_pub = Publisher(self._participant, qos=Qos(Policy.Partition(
                    partitions=[request_partition(self.security.user)])))
            self._writer = DataWriter(self._req_pub or self._participant, self._req_topic, qos=request_writer_qos())
        # Replies come in this client's own partition, from a writer the server makes at the first reply.
        with access_checked(self.security, "reply reader"):
            self._rep_sub = Subscriber(self._participant,
                                       qos=Qos(Policy.Partition(partitions=[reply_partition(self.client_id)])))
            self._replies = Inbox(self._participant, self._rep_topic, reply_reader_qos(), parent=self._rep_sub)

    # -- lifecycle -------------------------------------------------------------------------------
    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def attach(self, child: Any) -> None:
        """Registers a session or watcher (anything with ``close()``) to be closed with this client."""
        self._children.append(child)

    def detach(self, child: Any) -> None:
        """Forgets a child registered with :meth:`attach` (it closed itself)."""
        if child in self._children:
            self._children.remove(child)

    def close(self) -> None:
        """Closes sessions, watchers and DDS entities, then stops the server if this client spawned it."""
        if self._closed:
            return
        release_identity(self.security)
        if self._replies is None:  # the constructor failed part way (e.g. AccessDeniedError)
            self._closed = True
            _delete(self._rep_sub, self._writer, self._req_pub, self._rep_topic, self._req_topic, self._participant)
            return
        # Sessions detach so the server can drop sessions nobody uses; when no server is matched any
        # more (it exited) the client counts as closed first, so they only mark themselves closed.
        if publication_matched(self._writer) == 0 or (
                self._server_seen and not self.server_alive()):
            self._closed = True
        for child in list(self._children):
            try:
                child.close()
            except errors.SurfelEditError:
                _log.warning("closing %r failed", child, exc_info=True)
        self._closed = True
        self._replies.close()
        _delete(self._writer, self._req_pub, self._rep_sub, self._rep_topic, self._req_topic, self._upd_topic,
                self._participant)
        if self._server is not None:
            stop_process(self._server)
            self._server = None

    @property
    def closed(self) -> bool:
        return self._closed

    # -- matching ------------------------------------------------------------------------------
    def wait_for_server(self, timeout: float) -> bool:
        """Waits until a server's request reader is discovered; True if so (its reply writer for this
        client is made at the first reply)."""
        return wait_matched(self._participant, (self._writer,), timeout)

    def update_inbox(self, match_timeout: float = _WATCH_MATCH_S, compact: bool = False) -> Inbox:
        """A new reader of ``surfeledit_update`` (all sessions), returned once the server greeted it (its
        update writer matched the reader, so every later update reaches it) or after ``match_timeout``
        seconds (updates are volatile: earlier ones are never seen). The caller closes it; ``greeted``
        tells whether the wait succeeded. Greetings are ``Update`` samples with cause ``"watch"`` and no
        session; later ones (greeting other readers) may arrive too.
        ``compact``: read the compact encoding (PROTOCOL.md "Updates, compact") instead of doubles."""
        with access_checked(self.security, "update reader"):
            if self._upd_topic is None:
                self._upd_topic = Topic(self._participant, TOPIC_UPDATE, proto.Update)
            inbox = Inbox(self._participant, self._upd_topic, update_qos(),
                          partition=COMPACT_UPDATE_PARTITION if compact else None)
        deadline = time.monotonic() + match_timeout
        if wait_matched(self._participant, (inbox.reader,), match_timeout):
            inbox.await_greeting(max(0.0, deadline - time.monotonic()))
        return inbox

    # -- low-level request API -----------------------------------------------------------------
    def new_request(self, op: "proto.Op", session: str = "", **args: Any) -> "proto.Request":
        """Builds a request with the next request id; ``args`` are the IDL argument fields, e.g.
        ``deform=proto.Deform(...)`` (wrapped into the 0-or-1 element sequence)."""
        with self._lock:
            rid = self._next_id
            self._next_id += 1
        req = proto.Request(client_id=self.client_id, request_id=rid, session=session, op=op)
        for name, value in args.items():
            if not hasattr(req, name) or name in ("client_id", "request_id", "session", "op"):
                raise TypeError(f"unknown request argument {name!r}")
            setattr(req, name, list(value) if isinstance(value, (list, tuple)) else [value])
        return req

    def call(self, request: "proto.Request", check: bool = True, timeout: Optional[float] = None,
             retries: int = 1) -> "proto.Reply":
        """Sends ``request`` and returns its reply (matched on client id and request id).

        On timeout the same request (same id) is sent again up to ``retries`` times — the server
        answers a repeat from its reply cache — then :class:`~surfeledit.errors.RequestTimeoutError`
        is raised. When the server is gone, :class:`~surfeledit.errors.ServerGoneError` is raised, or
        with ``reconnect`` > 0 the request is re-sent until a restarted server answers (reconnect.py). With ``check`` a non-OK status raises the typed error of ``surfeledit.errors``.
        """
        if self._closed:
            raise errors.SurfelEditError("client is closed")
        timeout = self.timeout if timeout is None else timeout
        with self._lock:
            for attempt in range(retries + 1):
                self._writer.write(request)
                try:
                    reply = self._wait_reply(request.request_id, time.monotonic() + timeout)
                except errors.ServerGoneError:
                    if self.reconnect <= 0:
                        raise
                    reply = await_reply_across_restart(self, request, self.reconnect)
                if reply is not None:
                    break
                _log.warning("no reply to request %d (%s) within %.1f s%s", request.request_id,
                             _op_label(request.op), timeout, "; retrying" if attempt < retries else "")
            else:
                raise errors.RequestTimeoutError(
                    f"no reply to request {request.request_id} ({_op_label(request.op)}) on domain {self.domain} "
                    f"within {timeout:.1f} s (tried {retries + 1} times)")
        if int(reply.request_op) != int(request.op):
            raise errors.ReplyMismatchError(
                f"the reply to request {request.request_id} ({_op_label(request.op)}) answers op {int(reply.request_op)}; "
                "ignored", "request_op")
        if check and reply.status != proto.Status.STATUS_OK:
            raise errors.error_for_status(int(reply.status.value), reply.message, reply.field)
        return reply

    def request(self, op: "proto.Op", session: str = "", check: bool = True, **args: Any) -> "proto.Reply":
        """``call(new_request(op, session, **args))``."""
        return self.call(self.new_request(op, session, **args), check=check)

    def _wait_reply(self, request_id: int, deadline: float) -> Optional["proto.Reply"]:
        not_alive_since: Optional[float] = None
        while True:
            # Drain everything new; replies for other clients (same topic) and stale repeats are dropped.
            while True:
                samples = self._replies.take()
                if not samples:
                    break
                for s in samples:
                    if not isinstance(s, proto.Reply):
                        continue  # instance-state change without data
                    if s.client_id == self.client_id and s.request_id == request_id:
                        return s
            not_alive_since = self._check_server_alive(request_id, not_alive_since)
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            self._replies.wait(min(remaining, _GONE_POLL_S))

    def server_alive(self) -> bool:
        """Whether a reply writer (the server's) is matched and alive by DDS liveliness."""
        reader = self._replies.reader
        return _matched(reader) > 0 and alive_writers(reader) > 0

    def _check_server_alive(self, request_id: int, not_alive_since: Optional[float]) -> Optional[float]:
        """Raises ServerGoneError once a reply writer seen alive before has not been alive for
        _GONE_GRACE_S (a writer the server re-creates for this client matches within milliseconds);
        returns since when it is not alive (None: alive)."""
        if self.server_alive():
            self._server_seen = True
            return None
        now = time.monotonic()
        if not_alive_since is None:
            return now
        if self._server_seen and now - not_alive_since >= _GONE_GRACE_S:
            raise errors.ServerGoneError(
                f"the surfeledit server on domain {self.domain} is gone (its reply writer is no longer alive) "
                f"while request {request_id} waited for its reply")
        return not_alive_since

    # -- high-level API -------------------------------------------------------------------------
    def info(self, session: str = "") -> "proto.ServerInfo":
        """Server info (``version``, ``uptime_s``, ``sessions``, ``max_chunk_surfels``, ``max_model_surfels``)."""
        reply = self.request(proto.Op.OP_INFO, session)
        if not reply.server_info:
            raise errors.InternalServerError("OP_INFO reply without server_info", "server_info")
        self._server_info = reply.server_info[0]
        return self._server_info

    @property
    def max_chunk_surfels(self) -> int:
        """The server's per-chunk/page limit (from the last info; fetched if unknown)."""
        info = self._server_info or self.info()
        return int(info.max_chunk_surfels) or 65536

    def open_session(self, name: str) -> Session:
        """Creates the named session (or attaches if it exists)."""
        return Session(self, name, self.request(proto.Op.OP_OPEN_SESSION, name))

    def join_session(self, name: str, token: str = "") -> Session:
        """Attaches to an existing session: one this client is a member of, or another's with the
        ``token`` of an invitation (:meth:`Session.invite`), in the role it grants.
        :class:`~surfeledit.errors.NotFoundError` otherwise, the same whether the session exists or not."""
        request = self.new_request(proto.Op.OP_JOIN_SESSION, name)
        request.token = str(token)
        return Session(self, name, self.call(request))

    def probe(self, timeout: float) -> bool:
        """True if a server is discovered and answers OP_INFO within about ``timeout`` seconds."""
        if not self.wait_for_server(timeout):
            return False
        try:
            reply = self.call(self.new_request(proto.Op.OP_INFO), timeout=max(0.5, timeout), retries=1)
        except errors.RequestTimeoutError:
            return False
        self._server_info = reply.server_info[0] if reply.server_info else None
        return True


def connect(domain: Optional[int] = None, spawn: Optional[bool] = None, timeout: float = 10.0,
            data_root: Optional[Union[str, "os.PathLike[str]"]] = None, reconnect: float = 0.0,
            client_id: Optional[str] = None,
            security: Optional[Union[str, "os.PathLike[str]", SecurityConfig]] = None) -> Client:
    """Connects to the surfeledit server on a DDS domain.

    Args:
        domain: DDS domain id, 0..232 (the server's ``--domain`` range); None -> env ``SURFELEDIT_DOMAIN`` or 0.
        spawn: when no server answers ``OP_INFO`` within a short probe, start
            ``surfeledit-server --domain D`` (see :func:`~surfeledit.server_process.find_server_executable`),
            wait until it answers, and stop it when the client closes. None: True without
            ``security``, False with it (a secured server needs its own identity: start it yourself).
        timeout: seconds to wait for each reply (a request is retried once) and for a spawned
            server to come up.
        data_root: for a spawned server: the directory ``Session.load_file`` may read below
            (``--data-root``); None: file loading is off on that server.
        reconnect: seconds a request whose server is gone is re-sent (same request id) waiting for a
            restarted server (one with ``--journal`` answers it exactly once); 0: ServerGoneError at once.
        client_id: this client's id (None: a fresh unique one). Reuse the id of a process that died to
            reopen its sessions after the server detached it (``--client-lease-ms``) and before its
            grace period ended (``--session-grace-ms``); until the old one is detached the server
            does not answer the new one (the id is bound to the old writer), so the probe fails.
        security: DDS Security (PROTOCOL.md "Security"): a configuration file as
            ``scripts/make_security.py`` writes one per user, or a :class:`~surfeledit.security.SecurityConfig`.
            The participant authenticates with that identity and is encrypted; a fresh client id
            starts with ``"<user>."``. Needs a binding with the security plugins (``.venv-secure``).

    Raises:
        InvalidArgumentError: ``domain`` is not an integer in 0..232.
        ServerStartError: no server answered (spawn=False), or one could not be found/started.
        SecurityConfigError: ``security`` cannot be used (bad file, no plugins in this binding).
        AccessDeniedError: DDS Security refused this identity the participant or a surfeledit endpoint.
    """
    if domain is None:
        domain = os.environ.get("SURFELEDIT_DOMAIN", "0")
    client = Client(domain, timeout, reconnect=reconnect, client_id=client_id, security=security)
    if spawn is None:
        spawn = client.security is None
    try:
        # A secured participant is matched only after the authentication handshake: give it the timeout.
        if client.probe(timeout if client.security else min(_PROBE_S, timeout)):
            return client
        if not spawn:
            why = (" (with DDS Security: or the server did not authenticate this identity or its permissions)"
                   if client.security else "")
            raise errors.ServerStartError(f"no surfeledit server answers on DDS domain {domain}{why}")
        proc, log = spawn_server(domain, data_root)
        client._server, client._server_log = proc, log
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if client._server is not None and proc.poll() is not None:
                if proc.returncode != DOMAIN_TAKEN_EXIT_CODE:
                    raise errors.ServerStartError(exit_message(proc, log))
                # Another client spawned a server on this domain at the same time and that one started first
                # (PROTOCOL.md "One server per domain"): use it; it is not this client's to stop.
                _log.info("a server started first on domain %d; using it", domain)
                client._server = None
            if client._server is not None and not server_ready(log):
                time.sleep(0.02)  # until it serves or gives way: a server that answers now may be another one
                continue
            if client.probe(min(1.0, max(0.1, deadline - time.monotonic()))):
                return client
        raise errors.ServerStartError(f"{proc.args[0]} (pid {proc.pid}) did not answer OP_INFO within "
                                      f"{timeout:.1f} s (log: {log})")
    except BaseException:
        client.close()
        raise
