"""Errors that name the file, the field and what was expected."""

from __future__ import annotations


class SpecError(ValueError):
    """A declarative file or a recording does not match what b2d expects."""

    def __init__(self, path, field: str, expected: str, got=None):
        self.path = str(path) if path is not None else None
        self.field = field
        self.expected = expected
        self.got = got
        where = f"{self.path}: " if self.path else ""
        got_text = f" (got {got!r})" if got is not None else ""
        super().__init__(f"{where}field '{field}': expected {expected}{got_text}")

    def __reduce__(self):     # rebuilt from its parts when it crosses a process boundary (a worker's error)
        return type(self), (self.path, self.field, self.expected, self.got), self.__dict__


class UnknownNameError(KeyError):
    """An unknown task, embodiment, channel, profile or setting name; lists the valid ones."""

    def __init__(self, kind: str, name: str, valid):
        self.kind, self.name, self.valid = kind, name, sorted(valid)
        super().__init__(f"unknown {kind} '{name}'; valid {kind} names: {', '.join(self.valid)}")

    def __str__(self) -> str:  # KeyError would otherwise quote the whole message
        return self.args[0]

    def __reduce__(self):
        return type(self), (self.kind, self.name, self.valid), self.__dict__
