"""The server registers its topics with XTypes type information (proto/PROTOCOL.md, "Topics and QoS"),
so the standard DDS tools can show its types: `cyclonedds typeof <topic>` reconstructs the IDL over
XTypes type lookup, and `cyclonedds ls` shows a type id. Checked against the members declared in
proto/surfeledit.idl (parsed here independently of both generators).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import List

import pytest

from .conftest import REPO, ServerProcess, connect_to


def cyclonedds_tool() -> str:
    exe = shutil.which("cyclonedds", path=str(Path(sys.executable).parent)) or shutil.which("cyclonedds")
    if exe is None:
        pytest.skip("the `cyclonedds` command (pip package cyclonedds) is not installed")
    return exe


def idl_members(struct: str) -> List[str]:
    """Member names of `struct` in proto/surfeledit.idl."""
    text = (REPO / "proto" / "surfeledit.idl").read_text()
    body = re.search(r"struct\s+" + struct + r"\s*\{(.*?)\n\s*\};", text, re.S)
    assert body, struct
    names = []
    for line in body.group(1).splitlines():
        code = line.split("//")[0].strip()
        m = re.match(r"(?:@key\s+)?[\w:<>, ]+?\s+(\w+)\s*;$", code)
        if m:
            names.append(m.group(1))
    return names


def run_tool(args: List[str]) -> str:
    r = subprocess.run([cyclonedds_tool(), *args, "--suppress-progress-bar", "--color", "none"],
                       capture_output=True, text=True, timeout=60)
    return r.stdout + r.stderr


@pytest.mark.parametrize("topic, struct", [("surfeledit_request", "Request"), ("surfeledit_reply", "Reply"),
                                           ("surfeledit_update", "Update")])
def test_cyclonedds_typeof_shows_the_idl(server: ServerProcess, topic: str, struct: str) -> None:
    connect_to(server).close()  # the server is up and its endpoints exist
    out = run_tool(["typeof", topic, "-i", str(server.domain), "-r", "3s"])
    assert re.search(r"struct\s+" + struct + r"\b", out), out[-3000:]
    members = idl_members(struct)
    assert len(members) >= 5
    for name in members:
        assert re.search(r"\b" + name + r"\s*;", out), (name, out[-3000:])


def test_cyclonedds_ls_shows_type_ids(server: ServerProcess) -> None:
    connect_to(server).close()
    out = run_tool(["ls", "-i", str(server.domain), "-r", "3s"])
    for topic in ("surfeledit_request", "surfeledit_reply", "surfeledit_update"):
        assert topic in out, out[-3000:]
    assert "unset" not in out, out[-3000:]
