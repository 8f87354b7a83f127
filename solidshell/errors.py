"""Exceptions that carry a one-line message meant for the user.

The CLI turns :class:`InputError` into a single line on stderr and exit status 2,
:class:`IOFailure` into exit status 3 (with the path); library callers get ordinary
``ValueError`` / ``OSError`` subclasses they can catch.
"""


class InputError(ValueError):
    """Bad user input: unknown scene, malformed density, invalid material, bad mesh, ..."""


class SolverError(RuntimeError):
    """A solver could not proceed (non-finite state, singular system, unstable step)."""


class IOFailure(OSError):
    """Writing (or preparing) an output file failed: full disk, unwritable folder, ...

    ``path`` is the file or folder concerned; ``str(exc)`` is one line naming it."""

    def __init__(self, path, reason: str):
        super().__init__(f"{path}: {reason}")
        self.path = str(path)
        self.reason = str(reason)

    def __str__(self) -> str:
        return f"{self.path}: {self.reason}"

    @classmethod
    def from_oserror(cls, exc: OSError, path) -> "IOFailure":
        """An IOFailure for ``exc`` raised while writing ``path`` (the OSError's own file name wins
        when it has one: it is the exact file that failed)."""
        where = getattr(exc, "filename", None) or path
        return cls(where, exc.strerror or str(exc) or type(exc).__name__)
