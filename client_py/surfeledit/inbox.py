"""DDS reader plumbing of the client: an :class:`Inbox` per topic reader and waiting for matches."""

from __future__ import annotations

import logging
import time
from typing import Any, Iterable, List, Optional

from cyclonedds.core import DDSStatus, InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader, Subscriber
from cyclonedds.topic import Topic

from ._protocol import proto
from .dds_status import publication_matched, subscription_matched

__all__ = ["Inbox", "GreetingGate", "is_greeting", "wait_matched"]

_log = logging.getLogger("surfeledit")

_ANY_NEW = SampleState.NotRead | ViewState.Any | InstanceState.Any


def _ns(seconds: float) -> int:
    return max(0, int(seconds * 1e9))


def _delete(*entities: Any) -> None:
    """Deletes DDS entities now instead of at garbage collection (Entity.__del__ is idempotent)."""
    for e in entities:
        if e is not None:
            try:
                e.__del__()
            except Exception:  # pragma: no cover - best effort at teardown
                _log.debug("deleting %r failed", e, exc_info=True)


def _matched(entity: Any) -> int:
    """Number of matched remote endpoints of a writer (publications) or a reader (subscriptions)."""
    if isinstance(entity, DataWriter):
        return publication_matched(entity)
    return subscription_matched(entity)


def wait_matched(participant: DomainParticipant, entities: Iterable[Any], timeout: float) -> bool:
    """Waits up to ``timeout`` seconds until every writer / reader in ``entities`` has a match; True if so."""
    entities = list(entities)
    deadline = time.monotonic() + timeout
    ws = WaitSet(participant)
    try:
        for e in entities:
            e.set_status_mask(DDSStatus.PublicationMatched if isinstance(e, DataWriter)
                              else DDSStatus.SubscriptionMatched)
            ws.attach(e)
        while True:
            if all(_matched(e) > 0 for e in entities):
                return True
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return False
            ws.wait(_ns(min(remaining, 0.05)))
    finally:
        for e in entities:
            try:
                ws.detach(e)
                e.set_status_mask(0)
            except Exception:  # pragma: no cover
                pass
        _delete(ws)


def is_greeting(sample: Any) -> bool:
    """True for the server's greeting of a new watcher: an ``Update`` with cause ``"watch"`` and no session."""
    return isinstance(sample, proto.Update) and sample.cause == "watch" and not sample.session


class GreetingGate:
    """Which taken samples belong to a watcher's stream; pure logic, fed the lists that DDS takes return.

    The stream starts at the greeting (PROTOCOL.md "Updates"): samples taken in batches before the
    greeting's batch arrived before it and are dropped (the server may have been writing a multi-part
    update while its writer matched the reader: only its last parts would arrive). A take groups samples
    by instance (the topic's key, the session; the greeting is instance ``""``), so positions within one
    batch do not tell what was written before the greeting: every other sample of the greeting's batch
    belongs to the stream, those listed after the greeting as well as those listed before it.
    A caller that stops waiting (:meth:`release`) gets what was held and every later sample.
    """

    def __init__(self) -> None:
        self.greeted = False
        self._held: List[Any] = []

    def feed(self, batch: List[Any]) -> bool:
        """While waiting for the greeting: keeps ``batch`` (held for :meth:`release`); True once greeted."""
        if self.greeted:
            self._held.extend(batch)
        elif any(is_greeting(s) for s in batch):
            self.greeted = True
            self._held = [s for s in batch if not is_greeting(s)]
        else:
            self._held.extend(batch)
        return self.greeted

    @property
    def holding(self) -> bool:
        """True while samples wait for :meth:`release`."""
        return bool(self._held)

    def release(self) -> List[Any]:
        """The held samples (oldest first, each once)."""
        out, self._held = self._held, []
        return out

    def pass_on(self, batch: List[Any]) -> List[Any]:
        """A batch taken by the consumer: all of it (a greeting that arrives now, after the caller stopped
        waiting, marks the gate greeted but drops nothing: earlier samples were handed out already)."""
        if not self.greeted and any(is_greeting(s) for s in batch):
            self.greeted = True
        return batch


class Inbox:
    """A reader of one topic with a condition on new samples: :meth:`take` what arrived, :meth:`wait` for more."""

    def __init__(self, participant: DomainParticipant, topic: Topic, qos: Any,
                 parent: Optional[Subscriber] = None, partition: Optional[str] = None) -> None:
        """``parent``: a subscriber to read in (its partitions); ``partition``: read in this partition
        (a subscriber of the inbox's own, deleted with it)."""
        self._own_sub = None
        if partition is not None:
            parent = self._own_sub = Subscriber(participant, qos=Qos(Policy.Partition(partitions=[partition])))
        self.reader = DataReader(parent if parent is not None else participant, topic, qos=qos)
        self._cond = ReadCondition(self.reader, _ANY_NEW)
        self._waitset = WaitSet(participant)
        self._waitset.attach(self._cond)
        self._gate = GreetingGate()

    @property
    def greeted(self) -> bool:
        """True once the server's greeting arrived (:meth:`await_greeting`)."""
        return self._gate.greeted

    def take(self, n: int = 64) -> List[Any]:
        """Up to ``n`` new samples (instance-state changes without data included; check their type); more
        when samples of the greeting's batch were held by :meth:`await_greeting`."""
        if self._gate.holding:
            return self._gate.release()
        return self._gate.pass_on(self.reader.take(N=n, condition=self._cond))

    def wait(self, timeout: float) -> None:
        """Blocks until a new sample arrives or ``timeout`` seconds pass."""
        if not self._gate.holding:
            self._waitset.wait(_ns(timeout))

    def await_greeting(self, timeout: float) -> bool:
        """Waits up to ``timeout`` seconds for an ``Update`` with cause ``"watch"`` (PROTOCOL.md "Updates":
        the server writes one to each new watcher once its writer matched it; from then on the server
        writes every update to this reader). Which samples :meth:`take` then returns: :class:`GreetingGate`
        (those of the greeting's batch and later ones; without a greeting, all)."""
        deadline = time.monotonic() + timeout
        while True:
            if self._gate.greeted or self._gate.feed(self.reader.take(N=64, condition=self._cond)):
                return True
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return False
            self._waitset.wait(_ns(remaining))

    def matched(self) -> int:
        """Number of matched writers."""
        return _matched(self.reader)

    def close(self) -> None:
        _delete(self._waitset, self._cond, self.reader, self._own_sub)
