"""Typed exceptions for server errors.

Every non-OK ``Reply.status`` becomes one subclass of :class:`SurfelEditError`; the mapping follows
the ``Status`` enum of ``proto/surfeledit.idl`` (whose numbers equal the core's ``ErrorCode``)::

    1 STATUS_INVALID_ARGUMENT -> InvalidArgumentError (also a ValueError)
    2 STATUS_NOT_FOUND        -> NotFoundError
    3 STATUS_CONFLICT         -> ConflictError
    4 STATUS_TOO_LARGE        -> TooLargeError
    5 STATUS_IO               -> ServerIOError
    6 STATUS_INTERNAL         -> InternalServerError
    7 STATUS_PERMISSION_DENIED -> PermissionDeniedError (also a PermissionError)

The client itself raises :class:`RequestTimeoutError` when no reply arrives in time,
:class:`ServerGoneError` when the server's reply writer is no longer alive (DDS liveliness, about a
second after the server died), and :class:`ReplyMismatchError` when a reply carrying the request's
client id and request id answers another op or lacks the op's result. With DDS Security
(``connect(security=...)``) it raises :class:`SecurityConfigError` for a configuration it cannot use
and :class:`AccessDeniedError` when DDS Security refuses this identity the surfeledit topics.
"""

from __future__ import annotations

from typing import Dict, Optional, Type

__all__ = [
    "SurfelEditError", "InvalidArgumentError", "NotFoundError", "ConflictError", "TooLargeError",
    "ServerIOError", "InternalServerError", "RequestTimeoutError", "ServerStartError", "error_for_status",
    "PermissionDeniedError", "ServerGoneError", "ReplyMismatchError", "SecurityConfigError", "AccessDeniedError",
]


class SurfelEditError(Exception):
    """Base of every surfeledit error.

    Attributes:
        status: the ``Status`` number of the reply (0 for client-side errors such as timeouts
            or argument checks done before sending).
        field: the offending input as the server (or the client-side check) named it, e.g.
            ``"load_chunk.positions[12]"``, ``"deform.axis"``; empty when not applicable.
        message: human-readable explanation.
    """

    status: int = 0

    def __init__(self, message: str, field: str = "", status: Optional[int] = None) -> None:
        super().__init__(f"{message} (field: {field})" if field else message)
        self.message = message
        self.field = field
        if status is not None:
            self.status = status


class InvalidArgumentError(SurfelEditError, ValueError):
    """A value is malformed (NaN, wrong shape, zero normal, bad enum string, ...). Status 1."""

    status = 1


class NotFoundError(SurfelEditError):
    """Unknown session, id or file. Status 2."""

    status = 2


class ConflictError(SurfelEditError):
    """Well-formed but contradicts the state (overlapping regions, no regions set, not attached). Status 3."""

    status = 3


class TooLargeError(SurfelEditError):
    """Beyond a size limit of the server (``max_chunk_surfels``, ``max_model_surfels``). Status 4."""

    status = 4


class ServerIOError(SurfelEditError):
    """A file could not be read on the server. Status 5."""

    status = 5


class InternalServerError(SurfelEditError):
    """A server bug; the request changed nothing. Status 6."""

    status = 6


class PermissionDeniedError(SurfelEditError, PermissionError):
    """The caller's role in the session does not allow the op (a viewer changing it, a non-owner inviting). Status 7."""

    status = 7


class ServerGoneError(SurfelEditError, ConnectionError):
    """The server stopped answering: its reply writer lost its DDS liveliness or was unmatched."""

    status = 0


class ReplyMismatchError(SurfelEditError):
    """A reply with this request's ids answers another op or lacks the op's result (a forged or
    confused reply); nothing from it is used."""

    status = 0


class RequestTimeoutError(SurfelEditError, TimeoutError):
    """No reply arrived in time (after one retry with the same request id)."""

    status = 0


class ServerStartError(SurfelEditError, RuntimeError):
    """No server answered and none could be started (spawn=True) or found (spawn=False)."""

    status = 0


class SecurityConfigError(SurfelEditError, ValueError):
    """The client's DDS Security configuration cannot be used: a malformed file, a missing key or
    file, or a cyclonedds binding without the security plugins (use ``.venv-secure``). ``field``
    names the key."""

    status = 0


class AccessDeniedError(SurfelEditError, PermissionError):
    """DDS Security refused this participant: its identity or permissions are not valid for the
    domain, or its permissions do not allow a surfeledit topic or partition it needs (``field``:
    the entity refused, e.g. ``"reply reader"``). Nothing was sent."""

    status = 0


_BY_STATUS: Dict[int, Type[SurfelEditError]] = {
    1: InvalidArgumentError,
    2: NotFoundError,
    3: ConflictError,
    4: TooLargeError,
    5: ServerIOError,
    6: InternalServerError,
    7: PermissionDeniedError,
}


def error_for_status(status: int, message: str, field: str = "") -> SurfelEditError:
    """Returns the exception for a reply status number (an unknown number gives the base class)."""
    cls = _BY_STATUS.get(int(status))
    if cls is None:
        return SurfelEditError(f"unknown status {int(status)}: {message}", field, status=int(status))
    return cls(message, field)
