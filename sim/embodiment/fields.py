"""Errors of the robot description files, and the field path the loaders name when what a file refers to
does not match the rest of its hand or arm (a link, a joint, an actuator, a finger); keys, types and ranges
are the schema's (sim/schema)."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from sim.errors import SpecError


class DescriptionError(SpecError):
    """An arm, hand or embodiment file is missing a field or holds a value of the wrong shape.

    A SpecError (whoever catches those catches these); built like one, ``(path, field, expected, got)``,
    or from one finished message ``"<file>: field '<field>': ..."``."""

    def __init__(self, path_or_message, field: str | None = None, expected: str | None = None, got=None):
        if field is None:
            ValueError.__init__(self, path_or_message)
            self.path = self.field = self.expected = None
        else:
            super().__init__(path_or_message, field, expected, got)

    def __reduce__(self):
        if self.field is None:
            return type(self), (str(self),), self.__dict__
        return super().__reduce__()


def _expected_error(path, where: str, expected: str, got=None) -> DescriptionError:
    return DescriptionError(path, where, expected, got)


class _Ctx:
    """Carries the file path and a field path for error messages.

    ``error(path, field, expected, got)`` builds what ``expect`` raises (the tactile layer passes its
    ``TactileSpecError``); the message reads the same either way.
    """

    def __init__(self, path: Path | str | None, where: str = "", error: Callable = _expected_error):
        self.path = path
        self.where = where
        self.error = error

    def sub(self, key) -> "_Ctx":
        return _Ctx(self.path, f"{self.where}.{key}" if self.where else str(key), self.error)

    def fail(self, msg: str):
        raise DescriptionError(f"{self.path}: field '{self.where}': {msg}")

    def expect(self, expected: str, got=None):
        raise self.error(self.path, self.where, expected, got)
