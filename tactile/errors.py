"""Errors raised by the tactile layer; each names the file, the field and what was expected."""

from __future__ import annotations


class TactileSpecError(ValueError):
    """A pad description, tactile block or surface-map asset does not match what b2d expects."""

    def __init__(self, source, field: str, expected: str, got=None):
        self.source = str(source) if source is not None else None
        self.field = field
        self.expected = expected
        self.got = got
        where = f"{self.source}: " if self.source else ""
        got_text = f" (got {got!r})" if got is not None else ""
        super().__init__(f"{where}field '{field}': expected {expected}{got_text}")

    def __reduce__(self):     # rebuilt from its parts when it crosses a process boundary (a worker's error)
        return type(self), (self.source, self.field, self.expected, self.got), self.__dict__
