"""Errors a user can act on: each message names the bad input and the fix."""

from __future__ import annotations

__all__ = ["WorkbenchError", "InputError", "SpectrumFileError"]


class WorkbenchError(Exception):
    """Base class of errors the CLI reports as one message (exit status 2)."""


class InputError(WorkbenchError, ValueError):
    """A value handed to a function is unusable (NaN, negative, empty, wrong shape)."""


class SpectrumFileError(WorkbenchError, ValueError):
    """A spectrum or data file cannot be read; the message names file, line and fix."""

    def __init__(self, path, line: int | None, problem: str, fix: str):
        self.path, self.line, self.problem, self.fix = str(path), line, problem, fix
        where = f"{path}, line {line}" if line is not None else f"{path}"
        super().__init__(f"{where}: {problem}. Fix: {fix}")
