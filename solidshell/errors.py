"""Exceptions that carry a one-line message meant for the user.

The CLI turns :class:`InputError` into a single line on stderr and exit status 2;
library callers get an ordinary ``ValueError`` subclass they can catch.
"""


class InputError(ValueError):
    """Bad user input: unknown scene, malformed density, invalid material, bad mesh, ..."""


class SolverError(RuntimeError):
    """A solver could not proceed (non-finite state, singular system, unstable step)."""
