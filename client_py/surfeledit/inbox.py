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

__all__ = ["Inbox", "wait_matched"]

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
        self._early: List[Any] = []  # samples that arrived before the greeting (await_greeting)
        self.greeted = False

    def take(self, n: int = 64) -> List[Any]:
        """Up to ``n`` new samples (instance-state changes without data included; check their type)."""
        if self._early:
            out, self._early = self._early[:n], self._early[n:]
            return out
        return self.reader.take(N=n, condition=self._cond)

    def wait(self, timeout: float) -> None:
        """Blocks until a new sample arrives or ``timeout`` seconds pass."""
        if not self._early:
            self._waitset.wait(_ns(timeout))

    def await_greeting(self, timeout: float) -> bool:
        """Waits up to ``timeout`` seconds for an ``Update`` with cause ``"watch"`` (PROTOCOL.md "Updates":
        the server writes one to each new watcher once its writer matched it; from then on the server
        writes every update to this reader). Other samples that arrive first are kept for :meth:`take`."""
        deadline = time.monotonic() + timeout
        while True:
            for s in self.reader.take(N=64, condition=self._cond):
                if isinstance(s, proto.Update) and s.cause == "watch" and not s.session:
                    self.greeted = True
                    return True
                self._early.append(s)
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return False
            self._waitset.wait(_ns(remaining))

    def matched(self) -> int:
        """Number of matched writers."""
        return _matched(self.reader)

    def close(self) -> None:
        _delete(self._waitset, self._cond, self.reader, self._own_sub)
