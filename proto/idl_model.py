"""The model of a parsed IDL file: a ``Spec`` of enums and structs whose members refer to types
(primitives, sequences, earlier definitions). Built by idl_parser.py, read by idl2py.py's generator."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Union

__all__ = ["Spec", "Struct", "Enum", "Member", "Primitive", "Sequence_", "Named", "TypeRef", "Definition"]


@dataclass(frozen=True)
class Primitive:
    """A primitive type, spelled as in IDL (``unsigned long long``)."""

    name: str


@dataclass(frozen=True)
class Sequence_:
    """An unbounded ``sequence<element>``."""

    element: "TypeRef"


@dataclass(frozen=True)
class Named:
    """A reference to an earlier enum or struct, by fully scoped name (``surfeledit::proto::Vec3``)."""

    scoped: str


TypeRef = Union[Primitive, Sequence_, Named]


@dataclass
class Member:
    """One struct member; ``array_len`` is set for ``T name[N]``."""

    name: str
    type: TypeRef
    key: bool = False
    array_len: Optional[int] = None
    line: int = 0


@dataclass
class Enum:
    """``enum`` with its enumerators (values 0, 1, ... in order)."""

    scoped: str
    name: str
    enumerators: List[str]
    line: int = 0


@dataclass
class Struct:
    """``struct`` with its members in declaration order."""

    scoped: str
    name: str
    members: List[Member]
    line: int = 0


Definition = Union[Enum, Struct]


@dataclass
class Spec:
    """All definitions of one IDL file, in file order (dependencies always come first)."""

    file: str
    definitions: List[Definition] = field(default_factory=list)

    def by_scoped(self) -> Dict[str, Definition]:
        return {d.scoped: d for d in self.definitions}
