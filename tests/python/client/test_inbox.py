"""The update inbox (client_py/surfeledit/inbox.py): a watcher's stream starts at its greeting.

Two parts: the gate's pure logic (:class:`surfeledit.inbox.GreetingGate`, fed batches as one DDS take
returns them), and a real DDS reader and writer on their own domain (no server, no mocks) that write
samples before and after a greeting before the inbox takes any, so that they arrive in one batch.
"""

from __future__ import annotations

import time
from typing import List

from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic

from service import domains
from service.conftest import free_domain
from surfeledit._protocol import TOPIC_UPDATE, proto, update_qos
from surfeledit.inbox import GreetingGate, Inbox, wait_matched


def update(session: str, version: int, cause: str = "deform") -> "proto.Update":
    return proto.Update(session=session, version=version, cause=cause, parts=1, part=0)


def greeting() -> "proto.Update":
    return update("", 0, "watch")


def versions(samples: List["proto.Update"]) -> List[int]:
    return [int(s.version) for s in samples]


def test_gate_drops_batches_before_the_greetings_batch() -> None:
    gate = GreetingGate()
    assert not gate.feed([update("s", 1), update("s", 2)])
    assert not gate.feed([])
    assert gate.feed([update("s", 3), greeting(), update("t", 9)])
    assert gate.greeted
    assert [(s.session, int(s.version)) for s in gate.release()] == [("s", 3), ("t", 9)]
    assert gate.release() == [] and not gate.holding


def test_gate_keeps_every_sample_after_the_greeting_in_its_batch() -> None:
    """Several samples in the greeting's batch and in the next ones: none is dropped, order kept."""
    gate = GreetingGate()
    first = [greeting()] + [update("s", v) for v in range(1, 6)]
    assert gate.feed(first)
    assert versions(gate.release()) == [1, 2, 3, 4, 5]
    later = [update("s", v) for v in range(6, 10)] + [greeting()]  # another reader's greeting passes
    assert gate.pass_on(later) == later


def test_gate_greeting_listed_last_of_its_batch_keeps_the_rest() -> None:
    """A take lists instance by instance: the greeting (instance "") may come after samples of a session
    written after it."""
    gate = GreetingGate()
    assert gate.feed([update("s", 4), update("s", 5), greeting()])
    assert versions(gate.release()) == [4, 5]


def test_gate_without_greeting_hands_out_what_it_held() -> None:
    """The caller stopped waiting (not greeted): what arrived is handed out, then everything; a late
    greeting marks the gate greeted and drops nothing."""
    gate = GreetingGate()
    assert not gate.feed([update("s", 1)])
    assert versions(gate.release()) == [1]
    late = [update("s", 2), greeting(), update("s", 3)]
    assert gate.pass_on(late) == late and gate.greeted
    assert gate.feed([update("s", 4)])  # waiting again once greeted: kept
    assert versions(gate.release()) == [4]


def test_gate_after_a_late_greeting_drops_only_unreleased_samples() -> None:
    gate = GreetingGate()
    assert not gate.feed([update("s", 1)])
    assert not gate.feed([update("s", 2)])
    assert gate.feed([greeting(), update("s", 3)])
    assert versions(gate.release()) == [3]


class RealDDS:
    """A participant on its own domain with an update writer and an :class:`Inbox` matched to it."""

    def __init__(self) -> None:
        self.domain = free_domain()  # held by this process until close()
        self.dp = DomainParticipant(self.domain)
        topic = Topic(self.dp, TOPIC_UPDATE, proto.Update)
        self.writer = DataWriter(self.dp, topic, qos=update_qos())
        self.inbox = Inbox(self.dp, topic, update_qos())
        assert wait_matched(self.dp, (self.writer, self.inbox.reader), 10.0)

    def write(self, samples: List["proto.Update"]) -> None:
        for s in samples:
            self.writer.write(s)

    def take_until(self, count: int, timeout: float = 10.0) -> List["proto.Update"]:
        """Takes until ``count`` samples came (or the time is up), then once more for any extra."""
        got: List["proto.Update"] = []
        deadline = time.monotonic() + timeout
        while len(got) < count and time.monotonic() < deadline:
            got += self.inbox.take()
            if len(got) < count:
                self.inbox.wait(0.05)
        return got + self.inbox.take()

    def close(self) -> None:
        self.inbox.close()
        self.dp.__del__()
        domains.release(self.domain)


def test_real_reader_keeps_samples_after_the_greeting_in_its_batch() -> None:
    """The greeting and 5 updates are written before the inbox takes any: one batch holds them all."""
    dds = RealDDS()
    try:
        dds.write([greeting()] + [update("s", v) for v in range(1, 6)])
        dds.inbox.wait(5.0)
        time.sleep(0.2)  # all of them in the reader before the first take
        assert dds.inbox.await_greeting(10.0)
        assert versions(dds.take_until(5)) == [1, 2, 3, 4, 5]
    finally:
        dds.close()


def test_real_reader_starts_at_the_greetings_batch() -> None:
    """2 updates arrive and are taken while waiting; then the greeting and 2 more in one batch: the
    stream is the last 2."""
    dds = RealDDS()
    try:
        dds.write([update("s", 1), update("s", 2)])
        dds.inbox.wait(5.0)
        time.sleep(0.2)
        assert not dds.inbox.await_greeting(0.1)  # taken, held
        dds.write([greeting(), update("s", 3), update("s", 4)])
        dds.inbox.wait(5.0)
        time.sleep(0.2)
        assert dds.inbox.await_greeting(10.0)
        assert versions(dds.take_until(2)) == [3, 4]
    finally:
        dds.close()
