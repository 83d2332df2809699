"""Finding, starting and stopping a local ``surfeledit-server`` process (used by :func:`surfeledit.connect`)."""

from __future__ import annotations

import logging
import os
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path
from typing import List, Optional, Tuple, Union

from . import errors
from ._protocol import REPO_ROOT

__all__ = ["DOMAIN_TAKEN_EXIT_CODE", "find_server_executable", "server_args", "spawn_server", "server_ready",
           "exit_message", "stop_process"]

# The server's exit code when a server that started earlier serves its domain (PROTOCOL.md "One server per domain").
DOMAIN_TAKEN_EXIT_CODE = 4

_log = logging.getLogger("surfeledit")


def find_server_executable() -> Optional[str]:
    """The surfeledit-server to spawn: env ``SURFELEDIT_SERVER``, then ``PATH``, then the build tree."""
    env = os.environ.get("SURFELEDIT_SERVER")
    if env:
        return env
    found = shutil.which("surfeledit-server")
    if found:
        return found
    local = REPO_ROOT / "build" / "server" / "app" / "surfeledit-server"
    return str(local) if local.is_file() else None


def server_args(domain: int, data_root: Optional[Union[str, Path]] = None) -> List[str]:
    """The server's arguments: ``--domain D``, and ``--data-root DIR`` when given (file loading is off
    without it: ``Session.load_file`` reads only below that directory)."""
    args = ["--domain", str(domain)]
    if data_root is not None:
        args += ["--data-root", str(data_root)]
    return args


def spawn_server(domain: int, data_root: Optional[Union[str, Path]] = None) -> Tuple[subprocess.Popen, Path]:
    """Starts ``surfeledit-server --domain D [--data-root DIR]`` in its own session, output to a temporary
    log file.

    Returns the process and its log's path. Raises :class:`~surfeledit.errors.ServerStartError` when
    no executable is found (see :func:`find_server_executable`) or it cannot be started.
    """
    exe = find_server_executable()
    if exe is None:
        raise errors.ServerStartError(
            "no surfeledit server answers on DDS domain %d and surfeledit-server was not found "
            "(set SURFELEDIT_SERVER, put it on PATH, or build it into build/server/app)" % domain)
    log = tempfile.NamedTemporaryFile(prefix=f"surfeledit-server-{domain}-", suffix=".log", delete=False)
    argv = [exe] + server_args(domain, data_root)
    _log.info("starting %s (log: %s)", " ".join(argv), log.name)
    try:
        proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
    except OSError as e:
        raise errors.ServerStartError(f"cannot start {exe}: {e}") from e
    finally:
        log.close()
    return proc, Path(log.name)


def server_ready(log: Path) -> bool:
    """True once a spawned server's log says it serves (it logs "ready on domain" after its check for another
    server on the domain; before that, a server that answers may be another one)."""
    try:
        return "ready on domain" in log.read_text(errors="replace")
    except OSError:
        return False


def exit_message(proc: subprocess.Popen, log: Path) -> str:
    """Why a spawned server is gone: its exit code and the tail (2000 characters) of its log."""
    tail = log.read_text(errors="replace")[-2000:]
    return f"{proc.args[0]} exited with code {proc.returncode} before answering:\n{tail}"


def stop_process(proc: subprocess.Popen, grace: float = 5.0) -> None:
    """SIGTERM, wait up to ``grace`` seconds, then SIGKILL (nothing if it already exited)."""
    if proc.poll() is not None:
        return
    try:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        _log.warning("surfeledit-server (pid %d) ignored SIGTERM for %.0f s; killing it", proc.pid, grace)
        proc.kill()
        proc.wait()
