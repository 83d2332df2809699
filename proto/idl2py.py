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
import keyword
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

__all__ = ["IdlError", "parse", "generate", "generate_file", "main"]


class IdlError(Exception):
    """An IDL construct this generator does not understand (or a semantic error).

    The message has the form ``<file>:<line>: <what>``; ``file``, ``line`` and ``what``
    are also available as attributes.
    """

    def __init__(self, file: str, line: int, what: str) -> None:
        super().__init__(f"{file}:{line}: {what}")
        self.file = file
        self.line = line
        self.what = what


# --------------------------------------------------------------------------------------
# Model of the parsed IDL
# --------------------------------------------------------------------------------------

# IDL primitive spelling -> expression of the cyclonedds-python type.
PRIMITIVES: Dict[str, str] = {
    "boolean": "bool",
    "octet": "_t.uint8",
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


# --------------------------------------------------------------------------------------
# Tokenizer
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Token:
    kind: str  # "id", "int", "punct", "eof"
    text: str
    line: int


# One alternative per token class; anything that matches none of them is an error.
_TOKEN_RE = re.compile(
    r"""
    (?P<ws>[ \t\r\f\v]+)
  | (?P<nl>\n)
  | (?P<comment>//[^\n]*)
  | (?P<id>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<int>[0-9]+)
  | (?P<punct>::|[{}();:<>\[\],@=])
    """,
    re.VERBOSE,
)


def tokenize(text: str, file: str) -> List[Token]:
    """Splits IDL text into tokens, dropping whitespace and ``//`` comments.

    Raises IdlError on block comments, preprocessor directives and any other character.
    """
    tokens: List[Token] = []
    pos = 0
    line = 1
    while pos < len(text):
        if text.startswith("/*", pos):
            raise IdlError(file, line, "block comments '/* */' are not supported (use //)")
        if text[pos] == "#":
            raise IdlError(file, line, "preprocessor directives ('#...') are not supported")
        m = _TOKEN_RE.match(text, pos)
        if m is None:
            raise IdlError(file, line, f"unexpected character {text[pos]!r}")
        kind = m.lastgroup
        assert kind is not None
        if kind == "nl":
            line += 1
        elif kind in ("id", "int", "punct"):
            tokens.append(Token(kind, m.group(), line))
        pos = m.end()
    tokens.append(Token("eof", "", line))
    return tokens


# --------------------------------------------------------------------------------------
# Parser (recursive descent over the subset above)
# --------------------------------------------------------------------------------------

# Words that are IDL keywords for constructs we reject explicitly (clearer than "expected ...").
_UNSUPPORTED_KEYWORDS = {
    "union", "typedef", "const", "interface", "valuetype", "bitmask", "bitset", "map",
    "wstring", "wchar", "any", "fixed", "native", "exception", "attribute", "readonly",
    "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
    "include", "import", "switch", "case", "default", "abstract", "local", "custom",
}
_SUPPORTED_TYPE_ANNOTATIONS = {"final"}
_SUPPORTED_MEMBER_ANNOTATIONS = {"key"}


class _Parser:
    def __init__(self, tokens: List[Token], file: str) -> None:
        self.tokens = tokens
        self.pos = 0
        self.file = file
        self.spec = Spec(file)
        self.known: Dict[str, Definition] = {}  # scoped name -> definition
        self.py_names: Dict[str, str] = {}  # Python class name -> scoped name (collisions)

    # -- token helpers ------------------------------------------------------------------
    def peek(self, ahead: int = 0) -> Token:
        return self.tokens[min(self.pos + ahead, len(self.tokens) - 1)]

    def next(self) -> Token:
        tok = self.peek()
        self.pos += 1
        return tok

    def error(self, what: str, tok: Optional[Token] = None) -> IdlError:
        return IdlError(self.file, (tok or self.peek()).line, what)

    def describe(self, tok: Token) -> str:
        return "end of file" if tok.kind == "eof" else repr(tok.text)

    def expect(self, text: str) -> Token:
        tok = self.next()
        if tok.text != text or tok.kind == "eof":
            raise self.error(f"expected {text!r}, found {self.describe(tok)}", tok)
        return tok

    def identifier(self, what: str) -> Token:
        tok = self.next()
        if tok.kind != "id":
            raise self.error(f"expected {what}, found {self.describe(tok)}", tok)
        if tok.text in _UNSUPPORTED_KEYWORDS:
            raise self.error(f"{tok.text!r} is an IDL keyword and cannot be used as {what}", tok)
        if tok.text.startswith("_"):
            raise self.error(f"escaped identifiers ({tok.text!r}) are not supported", tok)
        return tok

    # -- grammar ------------------------------------------------------------------------
    def parse(self) -> Spec:
        self.definitions(scope=[])
        tok = self.peek()
        if tok.kind != "eof":
            raise self.error(f"unexpected {self.describe(tok)} at top level", tok)
        return self.spec

    def annotations(self, allowed: set, where: str) -> List[str]:
        """Reads ``@name`` annotations; rejects unknown ones and annotations with arguments."""
        names: List[str] = []
        while self.peek().text == "@" and self.peek().kind == "punct":
            at = self.next()
            name = self.next()
            if name.kind != "id":
                raise self.error(f"expected an annotation name after '@', found {self.describe(name)}", name)
            if self.peek().text == "(":
                raise self.error(f"annotation arguments (@{name.text}(...)) are not supported", name)
            if name.text not in allowed:
                raise self.error(f"annotation @{name.text} is not supported on {where} "
                                 f"(supported: {', '.join('@' + a for a in sorted(allowed))})", at)
            names.append(name.text)
        return names

    def definitions(self, scope: List[str]) -> None:
        """definition* up to a closing '}' (inside a module) or end of file."""
        while True:
            tok = self.peek()
            if tok.kind == "eof" or tok.text == "}":
                return
            if tok.text == "@":
                annos = self.annotations(_SUPPORTED_TYPE_ANNOTATIONS, "a type")
                kw = self.peek()
                if kw.text not in ("struct", "enum"):
                    raise self.error(f"annotations are only supported before 'struct' and 'enum', "
                                     f"found {self.describe(kw)}", kw)
                del annos  # only @final is accepted, which is the default anyway
                continue
            if tok.text == "module":
                self.module(scope)
            elif tok.text == "struct":
                self.struct(scope)
            elif tok.text == "enum":
                self.enum(scope)
            elif tok.text in _UNSUPPORTED_KEYWORDS:
                raise self.error(f"'{tok.text}' is not supported by idl2py", tok)
            else:
                raise self.error(f"expected 'module', 'struct' or 'enum', found {self.describe(tok)}", tok)

    def module(self, scope: List[str]) -> None:
        self.expect("module")
        name = self.identifier("a module name")
        self.expect("{")
        self.definitions(scope + [name.text])
        self.expect("}")
        self.expect(";")

    def declare(self, scope: List[str], name: Token) -> str:
        """Registers a new type name; rejects redefinitions and Python class-name collisions."""
        scoped = "::".join(scope + [name.text])
        if scoped in self.known:
            raise self.error(f"{scoped} is defined twice", name)
        if keyword.iskeyword(name.text):
            raise self.error(f"type name {name.text!r} is a Python keyword", name)
        if name.text in self.py_names:
            raise self.error(f"type name {name.text!r} ({scoped}) collides with {self.py_names[name.text]} "
                             f"in the flat generated Python module", name)
        self.py_names[name.text] = scoped
        return scoped

    def enum(self, scope: List[str]) -> None:
        kw = self.expect("enum")
        name = self.identifier("an enum name")
        scoped = self.declare(scope, name)
        self.expect("{")
        enumerators: List[str] = []
        while True:
            if self.peek().text == "@":
                raise self.error("annotations on enumerators (e.g. @value) are not supported")
            tok = self.identifier("an enumerator")
            if tok.text in enumerators:
                raise self.error(f"enumerator {tok.text} appears twice in {scoped}", tok)
            if keyword.iskeyword(tok.text):
                raise self.error(f"enumerator {tok.text!r} is a Python keyword", tok)
            enumerators.append(tok.text)
            sep = self.next()
            if sep.text == "}":
                break
            if sep.text != ",":
                raise self.error(f"expected ',' or '}}' in enum {scoped}, found {self.describe(sep)}", sep)
            if self.peek().text == "}":  # IDL does not allow a trailing comma
                raise self.error(f"trailing ',' in enum {scoped}")
        self.expect(";")
        definition = Enum(scoped, name.text, enumerators, kw.line)
        self.known[scoped] = definition
        self.spec.definitions.append(definition)

    def struct(self, scope: List[str]) -> None:
        kw = self.expect("struct")
        name = self.identifier("a struct name")
        if self.peek().text == ";":
            raise self.error(f"forward declarations (struct {name.text};) are not supported")
        if self.peek().text == ":":
            raise self.error("struct inheritance is not supported")
        scoped = self.declare(scope, name)
        self.expect("{")
        members: List[Member] = []
        while self.peek().text != "}":
            if self.peek().kind == "eof":
                raise self.error(f"unterminated struct {scoped}")
            members.extend(self.member(scope, scoped, members))
        self.expect("}")
        self.expect(";")
        if not members:
            raise self.error(f"struct {scoped} has no members (empty structs are not supported)", name)
        definition = Struct(scoped, name.text, members, kw.line)
        self.known[scoped] = definition
        self.spec.definitions.append(definition)

    def member(self, scope: List[str], owner: str, previous: List[Member]) -> List[Member]:
        annos = self.annotations(_SUPPORTED_MEMBER_ANNOTATIONS, "a member")
        line = self.peek().line
        type_ref = self.type_spec(scope)
        result: List[Member] = []
        while True:
            name = self.identifier("a member name")
            if keyword.iskeyword(name.text) or name.text in ("sample_info",):
                raise self.error(f"member name {name.text!r} is reserved in Python/cyclonedds", name)
            if name.text in self.py_names:
                raise self.error(f"member name {name.text!r} equals a type name, which would shadow the "
                                 f"type in the generated class body", name)
            if any(m.name == name.text for m in previous + result):
                raise self.error(f"member {name.text} appears twice in {owner}", name)
            array_len: Optional[int] = None
            if self.peek().text == "[":
                self.next()
                size = self.next()
                if size.kind != "int":
                    raise self.error(f"array size must be a decimal literal, found {self.describe(size)}", size)
                array_len = int(size.text)
                if array_len <= 0:
                    raise self.error(f"array size must be positive, found {array_len}", size)
                self.expect("]")
                if self.peek().text == "[":
                    raise self.error("multi-dimensional arrays are not supported")
            is_key = "key" in annos
            if is_key and (isinstance(type_ref, Sequence_) or array_len is not None):
                raise self.error("@key on sequences or arrays is not supported", name)
            result.append(Member(name.text, type_ref, is_key, array_len, line))
            sep = self.next()
            if sep.text == ";":
                return result
            if sep.text != ",":
                raise self.error(f"expected ';' after member {name.text}, found {self.describe(sep)}", sep)

    def type_spec(self, scope: List[str]) -> TypeRef:
        tok = self.peek()
        if tok.kind != "id" and tok.text != "::":
            raise self.error(f"expected a type, found {self.describe(tok)}", tok)
        # Multi-word primitives: (unsigned)? (short | long | long long)
        words: List[str] = []
        if tok.text == "unsigned":
            words.append(self.next().text)
            nxt = self.peek()
            if nxt.text not in ("short", "long"):
                raise self.error(f"expected 'short' or 'long' after 'unsigned', found {self.describe(nxt)}", nxt)
        if self.peek().text in ("short", "long"):
            first = self.next().text
            words.append(first)
            if first == "long" and self.peek().text == "long":
                words.append(self.next().text)
            elif first == "long" and self.peek().text == "double":
                raise self.error("'long double' is not supported")
            return Primitive(" ".join(words))
        tok = self.peek()
        if tok.text in ("boolean", "octet", "char", "float", "double"):
            self.next()
            return Primitive(tok.text)
        if tok.text == "string":
            self.next()
            if self.peek().text == "<":
                raise self.error("bounded strings (string<N>) are not supported")
            return Primitive("string")
        if tok.text == "sequence":
            self.next()
            self.expect("<")
            element = self.type_spec(scope)
            if self.peek().text == ",":
                raise self.error("bounded sequences (sequence<T, N>) are not supported")
            self.expect(">")
            return Sequence_(element)
        if tok.text in _UNSUPPORTED_KEYWORDS:
            raise self.error(f"type '{tok.text}' is not supported by idl2py", tok)
        return Named(self.resolve(scope))

    def resolve(self, scope: List[str]) -> str:
        """Reads a (possibly ``::``-qualified) name and resolves it against earlier definitions.

        IDL lookup: a relative name is searched in the current scope, then each enclosing one.
        """
        first = self.peek()
        absolute = False
        if first.text == "::":
            self.next()
            absolute = True
        parts = [self.identifier("a type name").text]
        while self.peek().text == "::":
            self.next()
            parts.append(self.identifier("a type name").text)
        rel = "::".join(parts)
        candidates = [rel] if absolute else ["::".join(scope[:i] + [rel]) for i in range(len(scope), -1, -1)]
        for cand in candidates:
            if cand in self.known:
                return cand
        raise self.error(f"unknown type {rel!r} (only enums and structs defined earlier in the file can be used)",
                         first)


def parse(text: str, file: str = "<idl>") -> Spec:
    """Parses IDL text (the subset described in the module docstring) into a ``Spec``."""
    return _Parser(tokenize(text, file), file).parse()


# --------------------------------------------------------------------------------------
# Code generation
# --------------------------------------------------------------------------------------


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
        "__all__ = [" + ", ".join(repr(d.name) for d in spec.definitions) + "]",
        "",
    ]
    for d in spec.definitions:
        out.append("")
        if isinstance(d, Enum):
            out.append(f"class {d.name}(_IdlEnum, typename={_typename(d.scoped)!r}):")
            out.append(f'    """IDL enum {d.scoped} (line {d.line})."""')
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
