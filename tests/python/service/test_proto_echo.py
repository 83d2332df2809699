"""Every IDL type survives C++ <-> Python: Python writes echo_in_<Type>, surfeledit-proto-echo (C,
built from the same IDL by idlc) republishes it on echo_out_<Type>, Python compares field by field."""

from __future__ import annotations

import dataclasses
import enum
import random
import time
import typing
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pytest
from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import types as idl_types
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from surfeledit._protocol import proto, request_qos

from .conftest import ManagedProcess, find_executable, free_domain

TOP_LEVEL = ["Request", "Reply", "Update"]


def random_value(tp: Any, rng: random.Random, depth: int = 0) -> Any:
    """A random, non-default value of a generated cyclonedds type annotation."""
    args = typing.get_args(tp)
    marker = args[1] if args else None
    if isinstance(marker, idl_types.sequence):
        return [random_value(marker.subtype, rng, depth + 1) for _ in range(rng.randint(1, 3))]
    if isinstance(marker, idl_types.array):
        return [random_value(marker.subtype, rng, depth + 1) for _ in range(marker.length)]
    if marker == "uint64":
        return rng.choice([rng.randrange(1, 2**64), 2**64 - 1, 2**63 + rng.randrange(1, 1000)])
    if marker == "uint32":
        return rng.randrange(1, 2**32)
    if marker == "int32":  # enum numbers carried as long, also outside their enum (PROTOCOL.md), and signed counts
        return rng.choice([rng.randrange(1, 2**31), -rng.randrange(1, 2**31), 99, -2**31, 2**31 - 1])
    if marker == "byte":  # IDL octet
        return rng.choice([rng.randrange(1, 255), 255, 0x80])
    if marker == "float64":
        return rng.choice([rng.uniform(-1e6, 1e6), rng.uniform(1e-300, 1e-9), 1.0 / 3.0, -2.5e300])
    if tp is bool:
        return True
    if tp is str:
        alphabet = "abcXYZ019_-. /äé"
        return "".join(rng.choice(alphabet) for _ in range(rng.randint(1, 24)))
    if isinstance(tp, type) and issubclass(tp, enum.Enum):
        members = list(tp)
        return rng.choice(members[1:])
    if dataclasses.is_dataclass(tp):
        return random_struct(tp, rng, depth + 1)
    raise AssertionError(f"no random generator for {tp!r}")


def random_struct(cls: Any, rng: random.Random, depth: int = 0) -> Any:
    hints = typing.get_type_hints(cls, include_extras=True)
    return cls(**{f.name: random_value(hints[f.name], rng, depth) for f in dataclasses.fields(cls)})


def plain(value: Any) -> Any:
    """A decoded value with arrays as lists (updates and state pages decode number sequences into arrays,
    surfeledit/wire_arrays.py), nested structs as dicts, so that == compares the numbers exactly."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, list):
        return [plain(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    return value


def test_random_values_are_not_defaults() -> None:
    rng = random.Random(1)
    for name in TOP_LEVEL:
        cls = getattr(proto, name)
        sample = random_struct(cls, rng)
        for f in dataclasses.fields(cls):
            assert getattr(sample, f.name) != getattr(cls(), f.name), f"{name}.{f.name}"


@pytest.fixture
def echo(tmp_path: Path) -> Iterator[ManagedProcess]:
    exe = find_executable("SURFELEDIT_PROTO_ECHO", "build/tests/surfeledit-proto-echo",
                          "build/server/app/surfeledit-proto-echo", "build*/**/surfeledit-proto-echo")
    if exe is None:
        pytest.skip("surfeledit-proto-echo not built (set SURFELEDIT_PROTO_ECHO)")
    domain = free_domain()
    proc = ManagedProcess([exe, "--domain", str(domain)], tmp_path / "echo.log")
    proc.domain = domain  # type: ignore[attr-defined]
    try:
        yield proc
    finally:
        proc.stop()


@pytest.mark.parametrize("type_name", TOP_LEVEL)
def test_round_trip_through_cpp(echo: ManagedProcess, type_name: str) -> None:
    cls = getattr(proto, type_name)
    rng = random.Random(20240611 + TOP_LEVEL.index(type_name))
    # Distinct keys so keep-all history per instance cannot mix samples up.
    samples = [random_struct(cls, rng) for _ in range(5)]

    dp = DomainParticipant(echo.domain)  # type: ignore[attr-defined]
    writer = DataWriter(dp, Topic(dp, f"echo_in_{type_name}", cls), qos=request_qos())
    reader = DataReader(dp, Topic(dp, f"echo_out_{type_name}", cls), qos=request_qos())
    cond = ReadCondition(reader, SampleState.NotRead | ViewState.Any | InstanceState.Any)
    ws = WaitSet(dp)
    ws.attach(cond)

    deadline = time.monotonic() + 20.0
    while (writer.get_publication_matched_status().current_count == 0
           or reader.get_subscription_matched_status().current_count == 0):
        assert echo.alive, f"surfeledit-proto-echo exited:\n{echo.log_tail()}"
        assert time.monotonic() < deadline, f"echo program never matched echo_in/out_{type_name}:\n{echo.log_tail()}"
        ws.wait(20_000_000)
    time.sleep(0.2)  # let the echo's writer discover our reader as well (volatile: no history)

    for s in samples:
        writer.write(s)
    received: list = []
    while len(received) < len(samples) and time.monotonic() < deadline:
        for r in reader.take(N=16, condition=cond):
            if isinstance(r, cls):
                received.append(r)
        if len(received) < len(samples):
            ws.wait(100_000_000)
    assert len(received) == len(samples), f"echoed {len(received)} of {len(samples)}:\n{echo.log_tail()}"
    for sent, got in zip(samples, received):
        for f in dataclasses.fields(cls):
            assert plain(getattr(got, f.name)) == plain(getattr(sent, f.name)), \
                f"{type_name}.{f.name} differs after C round trip"
