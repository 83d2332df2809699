"""The request fuzzer (tests/fuzz/request_fuzzer.py) for a bounded time against a real server, and the
regression tests of what it found. Longer runs: ``python tests/fuzz/request_fuzzer.py --seconds 600``;
``SURFELEDIT_FUZZ_SECONDS`` sets this test's budget (default 45 s, 0 skips it)."""

from __future__ import annotations

import importlib.util
import os

import pytest

import surfeledit
from surfeledit import proto

from .conftest import REPO, free_domain, server_executable

FUZZER = REPO / "tests" / "fuzz" / "request_fuzzer.py"


def load_fuzzer():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("request_fuzzer", FUZZER)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_request_fuzzer_finds_nothing_within_its_budget(monkeypatch: pytest.MonkeyPatch) -> None:
    seconds = float(os.environ.get("SURFELEDIT_FUZZ_SECONDS", "45"))
    if seconds <= 0:
        pytest.skip("SURFELEDIT_FUZZ_SECONDS=0")
    monkeypatch.setenv("SURFELEDIT_SERVER", server_executable())
    result = load_fuzzer().run(seconds, seed=int(os.environ.get("SURFELEDIT_FUZZ_SEED", "1")), domain=free_domain())
    assert result["requests"] > 100
    assert result["statuses"].get(0, 0) > 0  # it also got past validation


# Regression (fuzzer, seed 1, ~3200 requests): a setting with an empty name was refused with an empty
# `field`. Every error reply must name its field.
def test_a_setting_without_a_name_is_refused_naming_the_field(client: surfeledit.Client) -> None:
    client.open_session("s")
    req = client.new_request(proto.Op.OP_CONFIGURE, "s", configure=proto.Configure(
        settings=[proto.Setting(name="boundary_n", kind=3, number=4.0), proto.Setting(name="", kind=0, number=1.0)]))
    reply = client.call(req, check=False, timeout=3.0, retries=0)
    assert reply.status == proto.Status.STATUS_INVALID_ARGUMENT
    assert reply.field == "configure.settings[1].name", reply.field
