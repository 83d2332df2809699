"""The tokenizer of the IDL subset proto/idl2py.py reads: identifiers, decimal integers, punctuation;
whitespace and ``//`` comments dropped, everything else rejected with ``IdlError``."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import List

from idl_error import IdlError

__all__ = ["Token", "tokenize"]


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
