"""Communication statuses of DDS entities, the same way on both cyclonedds-python bindings the client runs on.

The client reads three statuses: how many remote endpoints a writer or reader is matched with, and
how many matched writers a reader sees alive (the server-liveliness watch behind ``ServerGoneError``).
cyclonedds-python 11 (the pip wheel of ``.venv``) has getters for them on the entity. The 0.10 binding
(``.venv-secure``, built from source against Debian's ``libddsc``, which has the DDS Security plugins)
has none, so there the same C functions of ``libddsc`` are called on the entity's handle with the
status structs that binding already declares. Either way the status is read on demand (no listener
runs on a DDS thread) and reading it does not reset what a waitset waits for: only the
``*_CHANGED`` fields and the status flag are consumed, which the client never uses.
"""

from __future__ import annotations

import ctypes
from typing import Any, Callable, Optional, Tuple

__all__ = ["publication_matched", "subscription_matched", "alive_writers", "binding_has_getters"]


def binding_has_getters() -> bool:
    """True on cyclonedds-python 11 (status getters on entities), False on 0.10."""
    from cyclonedds.pub import DataWriter
    return hasattr(DataWriter, "get_publication_matched_status")


_c_getters: Optional[Tuple[Callable[..., int], ...]] = None


def _c_functions() -> Tuple[Callable[..., int], ...]:
    """``dds_get_publication_matched_status``, ``dds_get_subscription_matched_status`` and
    ``dds_get_liveliness_changed_status`` of the ``libddsc`` the binding loaded, typed."""
    global _c_getters
    if _c_getters is None:
        from cyclonedds.internal import DDS, dds_c_t
        lib = DDS._dll_handle
        out = []
        for name, struct in (("dds_get_publication_matched_status", dds_c_t.publication_matched_status),
                             ("dds_get_subscription_matched_status", dds_c_t.subscription_matched_status),
                             ("dds_get_liveliness_changed_status", dds_c_t.liveliness_changed_status)):
            fn = getattr(lib, name)
            fn.restype = ctypes.c_int32
            fn.argtypes = [dds_c_t.entity, ctypes.POINTER(struct)]
            out.append(_bind(fn, struct, name))
        _c_getters = tuple(out)
    return _c_getters


def _bind(fn: Any, struct: Any, name: str) -> Callable[..., Any]:
    def get(entity: Any) -> Any:
        status = struct()
        rc = fn(entity._ref, ctypes.byref(status))
        if rc < 0:
            raise RuntimeError(f"{name} failed with DDS return code {rc}")
        return status
    return get


def publication_matched(writer: Any) -> int:
    """Number of readers the writer is matched with now (``current_count``)."""
    if hasattr(writer, "get_publication_matched_status"):
        return int(writer.get_publication_matched_status().current_count)
    return int(_c_functions()[0](writer).current_count)


def subscription_matched(reader: Any) -> int:
    """Number of writers the reader is matched with now (``current_count``)."""
    if hasattr(reader, "get_subscription_matched_status"):
        return int(reader.get_subscription_matched_status().current_count)
    return int(_c_functions()[1](reader).current_count)


def alive_writers(reader: Any) -> int:
    """Number of matched writers the reader sees alive by DDS liveliness (``alive_count``)."""
    if hasattr(reader, "get_liveliness_changed_status"):
        return int(reader.get_liveliness_changed_status().alive_count)
    return int(_c_functions()[2](reader).alive_count)
