#!/usr/bin/env python3
"""Generate cyclonedds-python topic types from the IDL subset used by surfeledit.

Why this exists: the ``idlc`` bundled with the cyclonedds 11.0.1 wheel crashes on start
(cyclonedds-python issue #336) and Debian's idlc 0.10.2 cannot load the 11.x Python plugin,
so the Python side of ``proto/surfeledit.idl`` is generated here, with the standard library only.

Supported (exactly what ``proto/surfeledit.idl`` needs, nothing more):

* ``//`` line comments;
* nested ``module name { ... };``
* ``enum Name { A, B, C };`` without explicit values (``@final`` or no annotation);
* ``struct Name { members };`` (``@final`` or no annotation; idlc's default is final too);
* members ``Type name;``, ``Type a, b;`` and fixed arrays ``Type name[N];`` (N a decimal literal,
  one dimension), optionally annotated ``@key``;
* types: ``boolean``, ``octet``, ``char``, ``short``, ``unsigned short``, ``long``,
  ``unsigned long``, ``long long``, ``unsigned long long``, ``float``, ``double``, unbounded
  ``string``, unbounded ``sequence<T>``, and names (``Name`` or ``a::b::Name``) of enums/structs
  defined earlier in the file.

Anything else (unions, typedefs, constants, bounded strings/sequences, block comments,
preprocessor lines, unknown annotations, forward references, ...) is rejected with an
``IdlError`` naming the file, line and the construct, instead of being guessed at.

Usage::

    python proto/idl2py.py proto/surfeledit.idl -o client_py/surfeledit/_proto.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Union

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the idl_*.py modules sit beside this file
# IdlError, parse and the Spec types are re-exported: callers and tests reach them as idl2py.<name>.
from idl_error import IdlError  # noqa: E402
from idl_model import Definition, Enum, Member, Named, Primitive, Sequence_, Spec, Struct, TypeRef  # noqa: E402,F401
from idl_parser import parse  # noqa: E402

__all__ = ["IdlError", "parse", "generate", "generate_file", "main"]


# --------------------------------------------------------------------------------------
# Code generation
# --------------------------------------------------------------------------------------


# IDL primitive spelling -> expression of the cyclonedds-python type.
PRIMITIVES: Dict[str, str] = {
    "boolean": "bool",
    "octet": "_byte",  # XTypes TK_BYTE, as idlc types IDL octet (generate() defines _byte per binding version)
    "char": "_t.char",
    "short": "_t.int16",
    "unsigned short": "_t.uint16",
    "long": "_t.int32",
    "unsigned long": "_t.uint32",
    "long long": "_t.int64",
    "unsigned long long": "_t.uint64",
    "float": "_t.float32",
    "double": "_t.float64",
    "string": "str",
}

# Default values (Python source) used for the generated dataclass fields.
PRIMITIVE_DEFAULTS: Dict[str, str] = {
    "boolean": "False",
    "char": "'\\x00'",
    "float": "0.0",
    "double": "0.0",
    "string": "''",
}


def _typename(scoped: str) -> str:
    # cyclonedds-python accepts "module.sub.Type" and maps it to the IDL name module::sub::Type.
    return scoped.replace("::", ".")


def _py_type(t: TypeRef, spec: Dict[str, Definition]) -> str:
    if isinstance(t, Primitive):
        return PRIMITIVES[t.name]
    if isinstance(t, Sequence_):
        return f"_t.sequence[{_py_type(t.element, spec)}]"
    return spec[t.scoped].name


def _default(t: TypeRef, spec: Dict[str, Definition], array_len: Optional[int]) -> str:
    """A ``dataclasses.field`` expression giving a fresh zero value of the member's type."""
    if array_len is not None:
        return f"_dc.field(default_factory=lambda: [{_scalar_default(t, spec)} for _ in range({array_len})])"
    if isinstance(t, Sequence_):
        return "_dc.field(default_factory=list)"
    if isinstance(t, Named) and isinstance(spec[t.scoped], Struct):
        return f"_dc.field(default_factory={spec[t.scoped].name})"
    return _scalar_default(t, spec)


def _scalar_default(t: TypeRef, spec: Dict[str, Definition]) -> str:
    if isinstance(t, Primitive):
        return PRIMITIVE_DEFAULTS.get(t.name, "0")
    if isinstance(t, Sequence_):
        return "[]"
    d = spec[t.scoped]
    if isinstance(d, Enum):
        return f"{d.name}.{d.enumerators[0]}"
    return f"{d.name}()"


def generate(spec: Spec, source_name: str = "") -> str:
    """Returns the Python source of a module defining one class per enum/struct of ``spec``."""
    defs = spec.by_scoped()
    out: List[str] = [
        f'"""cyclonedds-python topic types generated from {source_name or spec.file} by proto/idl2py.py.',
        "",
        "DO NOT EDIT: regenerate with",
        "    python proto/idl2py.py proto/surfeledit.idl -o client_py/surfeledit/_proto.py",
        '"""',
        "# fmt: off",
        "# Helpers are imported under underscore names so that IDL members (e.g. Reply.field)",
        "# cannot shadow them inside a class body; IDL identifiers never start with '_'.",
        "import dataclasses as _dc",
        "",
        "from cyclonedds.idl import IdlEnum as _IdlEnum, IdlStruct as _IdlStruct, types as _t",
        "from cyclonedds.idl.annotations import key as _key",
        "",
        "# IDL octet is XTypes TK_BYTE: types.byte in cyclonedds-python 11, types.uint8 in 0.10 (the",
        "# binding of .venv-secure, which maps uint8 to TK_BYTE); the same wire type either way.",
        "_byte = getattr(_t, 'byte', _t.uint8)",
        "",
        "__all__ = [" + ", ".join(repr(d.name) for d in spec.definitions) + "]",
        "",
    ]
    for d in spec.definitions:
        out.append("")
        if isinstance(d, Enum):
            # An int as well as an IdlEnum: the protocol carries some enum values in `long` fields
            # (Request.op, Selector.kind, Setting.kind), where a member is written as its number.
            out.append(f"class {d.name}(int, _IdlEnum, typename={_typename(d.scoped)!r}):")
            out.append(f'    """IDL enum {d.scoped} (line {d.line}); members are ints."""')
            for i, e in enumerate(d.enumerators):
                out.append(f"    {e} = {i}")
        else:
            out.append("@_dc.dataclass")
            out.append(f"class {d.name}(_IdlStruct, typename={_typename(d.scoped)!r}):")
            out.append(f'    """IDL @final struct {d.scoped} (line {d.line})."""')
            for m in d.members:
                py = _py_type(m.type, defs)
                if m.array_len is not None:
                    py = f"_t.array[{py}, {m.array_len}]"
                out.append(f"    {m.name}: {py} = {_default(m.type, defs, m.array_len)}")
                if m.key:
                    out.append(f"    _key({m.name!r})")
        out.append("")
    out.append("")
    out.append("# IDL scoped name -> generated class")
    out.append("IDL_TYPES = {")
    for d in spec.definitions:
        out.append(f"    {d.scoped!r}: {d.name},")
    out.append("}")
    out.append("")
    return "\n".join(out)


def generate_file(idl_path: Union[str, Path]) -> str:
    """Parses the IDL file at ``idl_path`` and returns the generated Python source."""
    path = Path(idl_path)
    spec = parse(path.read_text(encoding="utf-8"), str(path))
    return generate(spec, path.name)


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("idl", help="IDL file (the subset of proto/surfeledit.idl)")
    ap.add_argument("-o", "--output", required=True, help="Python module to write")
    args = ap.parse_args(argv)
    try:
        source = generate_file(args.idl)
    except IdlError as e:
        print(f"idl2py: error: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"idl2py: error: {e}", file=sys.stderr)
        return 1
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    # Write atomically so a concurrent import never sees a half-written module.
    tmp = out.with_suffix(out.suffix + ".tmp")
    tmp.write_text(source, encoding="utf-8")
    tmp.replace(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
