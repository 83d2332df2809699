"""The parser of proto/idl2py.py: the IDL subset surfeledit uses, parsed into a ``Spec`` (idl_model.py)
by recursive descent over the tokens of idl_lexer.py.

What is supported and what is rejected is listed in idl2py.py's docstring; anything else raises
``IdlError`` naming the file, line and construct.
"""

from __future__ import annotations

import keyword
from typing import Dict, List, Optional

from idl_error import IdlError
from idl_lexer import Token, tokenize
from idl_model import Definition, Enum, Member, Named, Primitive, Sequence_, Spec, Struct, TypeRef

__all__ = ["parse"]


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
