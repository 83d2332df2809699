"""Updates and state pages decode their number sequences into numpy arrays (surfeledit/wire_arrays.py) holding
exactly the numbers that were written: every sequence field, both byte orders, both CDR versions, extreme values,
empty sequences, nested pages. The truth is the sample written (its Python lists), not another decoder."""

from __future__ import annotations

import dataclasses
import typing
from typing import Any, Dict

import numpy as np
import pytest
from cyclonedds.idl import types as idl_types
from cyclonedds.idl._support import Endianness

from surfeledit import wire_arrays
from surfeledit._protocol import proto

# Wire element type -> (numpy dtype, extreme values to include).
ELEMENTS: Dict[str, Any] = {
    "float64": (np.float64, [0.0, -0.0, 1e-308, 5e-324, -1.7976931348623157e308, np.inf, -np.inf, 1.0 / 3.0]),
    "float32": (np.float32, [0.0, -0.0, 1e-38, 3.4028234663852886e38, np.inf]),
    "uint64": (np.uint64, [0, 1, 2**63, 2**64 - 1]),
    "uint32": (np.uint32, [0, 1, 2**31, 2**32 - 1]),
    "int32": (np.int32, [0, -1, -2**31, 2**31 - 1]),
    "int16": (np.int16, [0, -1, -2**15, 2**15 - 1]),
    "byte": (np.uint8, [0, 1, 0x80, 255]),
    "uint8": (np.uint8, [0, 1, 0x80, 255]),
}


def number_sequences(cls: Any) -> Dict[str, str]:
    """Field name -> wire element type of every sequence of numbers of a generated type."""
    out = {}
    for name, hint in typing.get_type_hints(cls, include_extras=True).items():
        args = typing.get_args(hint)
        marker = args[1] if len(args) > 1 else None
        element = typing.get_args(marker.subtype) if isinstance(marker, idl_types.sequence) else ()
        if len(element) > 1 and isinstance(element[1], str):
            out[name] = element[1]
    return out


def filled(cls: Any, rng: np.random.Generator, empty: bool = False) -> Any:
    """A sample of `cls` whose number sequences hold random values and every extreme of their type (or nothing)."""
    values = {}
    for name, element in number_sequences(cls).items():
        dtype, extremes = ELEMENTS[element]
        if empty:
            values[name] = []
            continue
        info = np.finfo(dtype) if np.issubdtype(dtype, np.floating) else np.iinfo(dtype)
        if np.issubdtype(dtype, np.floating):
            drawn = rng.normal(size=37) * rng.choice([1e-30, 1.0, 1e30], size=37)
        else:
            drawn = rng.integers(int(info.min), int(info.max), size=37, dtype=dtype, endpoint=True)
        values[name] = np.concatenate([np.asarray(extremes, dtype), drawn.astype(dtype)]).tolist()
    return cls(**values)


def test_the_project_bindings_decode_updates_and_pages_into_arrays() -> None:
    # Every number sequence of both types was given the array decoder at import (a second call finds none left).
    assert set(number_sequences(proto.Update)) >= {"ids", "positions", "normals", "radii", "removed", "colliding",
                                                   "clip_points", "clip_dirs", "origin", "positions_f32"}
    assert wire_arrays.install([proto.Update, proto.StatePage]) == 0
    sample = proto.Update.deserialize(filled(proto.Update, np.random.default_rng(3)).serialize())
    for name in number_sequences(proto.Update):
        assert isinstance(getattr(sample, name), np.ndarray), name


@pytest.mark.parametrize("cls_name", ["Update", "StatePage"])
@pytest.mark.parametrize("endianness", [Endianness.Little, Endianness.Big])
@pytest.mark.parametrize("version_2", [True, False])
def test_decoded_arrays_hold_exactly_the_numbers_written(cls_name: str, endianness: Endianness,
                                                        version_2: bool) -> None:
    cls = getattr(proto, cls_name)
    rng = np.random.default_rng(7)
    for empty in (False, True):
        sent = filled(cls, rng, empty)
        got = cls.deserialize(sent.serialize(endianness=endianness, use_version_2=version_2))
        for name, element in number_sequences(cls).items():
            dtype = ELEMENTS[element][0]
            arr = getattr(got, name)
            assert isinstance(arr, np.ndarray) and arr.dtype == np.dtype(dtype) and arr.dtype.isnative, name
            want = np.asarray(getattr(sent, name), dtype)
            assert arr.shape == want.shape, name
            assert arr.tobytes() == want.tobytes(), f"{cls_name}.{name} differs"  # bit for bit (-0.0, inf)
            arr[:1] = 0  # writable: the sample owns its arrays
        for f in dataclasses.fields(cls):  # the other fields as the binding decodes them
            if f.name not in number_sequences(cls):
                assert getattr(got, f.name) == getattr(sent, f.name), f.name


def test_pages_nested_in_a_reply_decode_into_arrays_and_arrays_are_sent_alike() -> None:
    rng = np.random.default_rng(11)
    pages = [filled(proto.StatePage, rng), filled(proto.StatePage, rng, empty=True)]
    reply = proto.Reply(state=pages)
    got = proto.Reply.deserialize(reply.serialize())
    for sent_page, got_page in zip(pages, got.state):
        for name, element in number_sequences(proto.StatePage).items():
            want = np.asarray(getattr(sent_page, name), ELEMENTS[element][0])
            assert getattr(got_page, name).tobytes() == want.tobytes(), name
    # A decoded sample (arrays) serialises to the same bytes as the one written from lists.
    update = filled(proto.Update, rng)
    decoded = proto.Update.deserialize(update.serialize())
    assert decoded.serialize() == update.serialize()


@pytest.mark.parametrize("cls_name", ["Update", "StatePage", "LoadChunk"])
def test_arrays_of_the_element_type_are_sent_as_the_same_bytes_as_lists(cls_name: str) -> None:
    cls = getattr(proto, cls_name)
    assert wire_arrays.sends_arrays(cls)
    lists = filled(cls, np.random.default_rng(5))
    arrays = cls(**{f.name: getattr(lists, f.name) for f in dataclasses.fields(cls)})
    for name, element in number_sequences(cls).items():
        setattr(arrays, name, np.asarray(getattr(lists, name), ELEMENTS[element][0]))
    for endianness in (Endianness.Little, Endianness.Big):
        for version_2 in (True, False):
            assert (arrays.serialize(endianness=endianness, use_version_2=version_2) ==
                    lists.serialize(endianness=endianness, use_version_2=version_2))


def test_other_arrays_are_checked_as_lists_are() -> None:
    # Another dtype goes out as a list, so the binding's own checks apply: an id must be a non-negative integer.
    bad = proto.Update(ids=np.array([1.5, 2.0]))
    with pytest.raises(Exception):
        bad.serialize()
    with pytest.raises(Exception):
        proto.Update(ids=[1.5, 2.0]).serialize()
    # A non-native byte order or a signed array of valid values is written like the list of its values.
    assert (proto.Update(positions=np.array([1.0, -2.0], ">f8")).serialize() ==
            proto.Update(positions=[1.0, -2.0]).serialize())
    assert proto.Update(ids=np.array([3, 4], np.int64)).serialize() == proto.Update(ids=[3, 4]).serialize()
