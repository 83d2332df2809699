"""Sequences of numbers in received samples as numpy arrays (the surfels' geometry of updates and state pages).

cyclonedds-python reads an IDL ``sequence<double>`` (or of any other number type) into a Python list: one Python
object per number, which the client then turns back into an array. For an update of a 1M-surfel step (288k rows,
18 MB) that decoding is most of what a Python watcher pays (bench/RESULTS.md §71-§72). :func:`install` makes the
listed topic types read those sequences straight into numpy arrays instead: the same numbers, the same wire format,
only what a decoded sample holds changes (an ``ndarray`` of the sequence's type, native byte order, writable, where
the binding gave a ``list``). Sending takes lists as before and, for these types, 1-D arrays of the element type,
written as one block of bytes (:func:`sends_arrays`; the same bytes as the list).

The binding offers no public hook for this: :func:`install` replaces, in the types' built decoders, the decoder of
each plain sequence of numbers by :class:`_ArraySequence`, which reads the same bytes through the buffer's public
``align`` / ``read`` / ``read_bytes``. When the binding is not laid out as expected (another version), nothing is
replaced and samples keep their lists: every reader of these fields goes through ``numpy.asarray``, so both work.
"""

from __future__ import annotations

import logging
from typing import Any, Iterable, Set

import numpy as np

_log = logging.getLogger(__name__)

try:  # pragma: no branch - both bindings the project supports (cyclonedds 11.0.1 and 0.10.2) have them
    from cyclonedds.idl import _machinery as _m
    from cyclonedds.idl._support import Endianness as _Endianness

    _SequenceMachine: Any = _m.PlainCdrV2SequenceOfPrimitiveMachine
    _StructMachine: Any = _m.StructMachine
except (ImportError, AttributeError):  # pragma: no cover - another binding layout
    _m = None
    _SequenceMachine = _StructMachine = None


if _SequenceMachine is not None:

    class _ArraySequence(_SequenceMachine):  # type: ignore[misc, valid-type]
        """A plain sequence of numbers read into an ndarray (written as the binding's own decoder writes it)."""

        def __init__(self, stock: Any) -> None:  # takes over the stock decoder's fields (code, size, alignment, bound)
            self.__dict__.update(stock.__dict__)
            self.dtype = np.dtype(self.code)
            if self.dtype.itemsize != self.size:
                raise TypeError(f"sequence element {self.code!r} is {self.size} bytes on the wire")

        def serialize(self, buffer: Any, value: Any, *args: Any, **kwargs: Any) -> Any:
            # A 1-D array of exactly the element type goes out as one block of bytes; anything else as the binding
            # writes it (other arrays as lists, so that their values are checked as the binding checks them).
            if not isinstance(value, np.ndarray):
                return super().serialize(buffer, value, *args, **kwargs)
            if value.ndim != 1 or value.dtype.newbyteorder("=") != self.dtype:
                return super().serialize(buffer, value.tolist(), *args, **kwargs)
            if self.max_length is not None and len(value) > self.max_length:
                raise ValueError(f"sequence of {len(value)} elements exceeds its bound {self.max_length}")
            buffer.align(4)
            buffer.write("I", 4, len(value))
            if len(value):
                buffer.align(self.alignment)
                order = "<" if buffer.endianness == _Endianness.Little else ">"
                buffer.write_bytes(np.ascontiguousarray(value, self.dtype.newbyteorder(order)).tobytes())
            return None

        def deserialize(self, buffer: Any, *args: Any, **kwargs: Any) -> np.ndarray:
            buffer.align(4)
            length = buffer.read("I", 4)
            if self.max_length is not None and length > self.max_length:
                raise ValueError(f"sequence of {length} elements exceeds its bound {self.max_length}")
            if not length:
                return np.empty(0, self.dtype)
            buffer.align(self.alignment)
            raw = buffer.read_bytes(self.size * length)
            order = "<" if buffer.endianness == _Endianness.Little else ">"
            return np.frombuffer(raw, self.dtype.newbyteorder(order)).astype(self.dtype)


_installed: Set[Any] = set()


def sends_arrays(cls: Any) -> bool:
    """Whether samples of ``cls`` may carry 1-D numpy arrays in their number sequences (install() gave it the array
    decoder): an array of the element type is then written as one block. Otherwise pass lists."""
    return cls in _installed


def install(types: Iterable[Any]) -> int:
    """Makes each generated topic type in ``types`` decode its plain sequences of numbers into ndarrays.

    Returns how many sequence decoders were replaced (0 when the binding is not laid out as expected: samples
    then keep their lists). Idempotent; nested types are decoded by their own type's decoders, so list them too.
    """
    if _SequenceMachine is None:
        return 0
    replaced = 0
    for cls in types:
        idl = getattr(cls, "__idl__", None)
        if idl is None or not hasattr(idl, "populate"):
            continue
        idl.populate()
        for name in ("v0_machine", "v1_machine", "v2_machine"):
            machine = getattr(idl, name, None)
            members = getattr(machine, "members_machines", None)
            if not isinstance(machine, _StructMachine) or not isinstance(members, dict):
                continue
            for field, sub in list(members.items()):
                if type(sub) is _SequenceMachine:
                    try:
                        members[field] = _ArraySequence(sub)
                    except (TypeError, KeyError, AttributeError) as exc:  # pragma: no cover - another layout
                        _log.debug("%s.%s keeps the binding's list decoder: %s", cls.__name__, field, exc)
                        continue
                    replaced += 1
                    _installed.add(cls)
    return replaced
