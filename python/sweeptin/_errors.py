"""The exceptions raised by sweeptin, one per kind of library error.

Every one is a :class:`SweeptinError`, and also the built-in class a Python user would catch
for that kind of problem (``ValueError`` for bad data or options, ``OSError`` for files).
Where the library knows it, the exception carries ``path`` (the file), ``line`` (1-based) or
``index`` (0-based point index) as attributes. Every one raised by the library also carries
``kind`` (``"usage"``, ``"input"``, ``"output"``, ``"internal"``) and ``exit_code`` (2, 3, 4,
5): the command line's exit status for the same failure, for batch scripts that report as it
does; so does one the package raises itself (an :class:`OptionsError` is ``"usage"``, 2).
"""

from __future__ import annotations


class SweeptinError(Exception):
    """Base class of every sweeptin error."""

    path: str | None = None
    line: int | None = None
    index: int | None = None
    kind: str | None = None
    exit_code: int | None = None


class InputError(SweeptinError, ValueError):
    """The data cannot be used: a non-finite or out-of-range coordinate, a damaged or
    unreadable file, a bad line of a text file, a breakline that cannot be used."""

    kind = "input"
    exit_code = 3


class NoTriangleError(InputError):
    """No triangle exists: fewer than 3 distinct (x, y) positions, or all of them on one line,
    or the filters left too few points (the message says what each filter dropped)."""


class OptionsError(SweeptinError, ValueError):
    """Options that cannot be used (a bad value, options that do not go together, no input,
    an output that would overwrite an input or another output)."""

    kind = "usage"
    exit_code = 2


class FileError(SweeptinError, OSError):
    """Reading or writing a file failed (the operating system's error: disk full, read-only,
    permissions); ``kind`` says which (``"input"`` reading, ``"output"`` writing an output or a
    temporary file)."""


class MissingFileError(FileError, FileNotFoundError):
    """A file or directory does not exist."""


class OutputError(SweeptinError, OSError):
    """An output cannot be written as asked (unknown format, a limit of the format, a
    directory or device in the way)."""

    kind = "output"
    exit_code = 4


class OutOfMemoryError(SweeptinError, MemoryError):
    """A buffer the job needs cannot be allocated within memory (or within ``mem``): the
    message says what for and what to do."""

    kind = "output"
    exit_code = 4


class InternalError(SweeptinError, RuntimeError):
    """A bug in sweeptin: please report it with the input."""

    kind = "internal"
    exit_code = 5


__all__ = [
    "SweeptinError",
    "InputError",
    "NoTriangleError",
    "OptionsError",
    "FileError",
    "MissingFileError",
    "OutputError",
    "OutOfMemoryError",
    "InternalError",
]
