"""The one error of the IDL tools (proto/idl2py.py and its lexer and parser)."""

__all__ = ["IdlError"]


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
