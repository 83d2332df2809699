"""The server's DDS transport defaults (dds::make_domain, RESULTS §68): DDSI fragments of 65000 bytes in
messages of up to 65500 instead of Cyclone's 1344 and 14720, under the configuration CYCLONEDDS_URI names, whose
settings win. Read back from Cyclone's own configuration trace of a real server."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Callable, Dict

import pytest

from .conftest import ServerProcess


def traced_config(start_server: Callable[..., ServerProcess], monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                  general: str) -> Dict[str, int]:
    """The server's General/* byte sizes as its Cyclone trace lists them, with `general` (an XML fragment or
    "") in the CYCLONEDDS_URI it is started with."""
    trace = tmp_path / "cyclonedds-trace.log"
    monkeypatch.setenv("CYCLONEDDS_URI",
                       f'<CycloneDDS><Domain id="any">{general}<Tracing><Category>config</Category>'
                       f"<OutputFile>{trace}</OutputFile></Tracing></Domain></CycloneDDS>")
    srv = start_server()
    try:
        srv.wait_ready()
    finally:
        srv.stop()
    sizes: Dict[str, int] = {}
    for line in trace.read_text(errors="replace").splitlines():
        m = re.search(r"config: Domain/General/(\w+)/#text: (\d+) B", line)
        if m:
            sizes[m.group(1)] = int(m.group(2))
    return sizes


def test_large_fragments_by_default(start_server: Callable[..., ServerProcess], monkeypatch: pytest.MonkeyPatch,
                                    tmp_path: Path) -> None:
    sizes = traced_config(start_server, monkeypatch, tmp_path, "")
    assert sizes.get("FragmentSize") == 65000, sizes
    assert sizes.get("MaxMessageSize") == 65500, sizes


def test_the_users_configuration_wins(start_server: Callable[..., ServerProcess], monkeypatch: pytest.MonkeyPatch,
                                      tmp_path: Path) -> None:
    sizes = traced_config(start_server, monkeypatch, tmp_path, "<General><FragmentSize>2000B</FragmentSize></General>")
    assert sizes.get("FragmentSize") == 2000, sizes
    assert sizes.get("MaxMessageSize") == 65500, sizes
