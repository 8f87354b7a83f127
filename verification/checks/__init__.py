"""The checks of solidshell against independent references, run by ``solidshell verify``.

    solidshell verify [NAME ...] [--quick] [--out DIR] [--list] [--references] [--fenicsx]

Each *check* (``--list`` names them) measures quantities against a reference that does not come
from this code -- a closed form, a published table, an ODE solved to 1e-10, another finite-element
code (scikit-fem, DOLFINx, Kratos) -- and returns one record per quantity.  The run prints one line
per record and writes ``verification.json``, ``report.md`` and ``figures/*.png`` to ``--out``
(default ``verification-out/``).  Exit status: 0 all passed (skipped records do not fail), 1 a
record failed or a check raised, 2 an unknown check name or a missing optional code (one line),
3 the output folder is not writable.

Record format (``verification.json`` "records", :class:`record.Record`; other codes' cross-checks,
e.g. ``verification/fenicsx/crosscheck.py``'s ``main(out_dir) -> list[dict]``, return the same):

    name            str    unique, "check/case/quantity" (e.g. "strip/warp/20x1/tip_z")
    reference       str    what the reference is ("heavy elastica, warp")
    source          str    the script or publication it comes from
    quantity        str    what is measured, with units
    value           float  ours (None when skipped)
    reference_value float  the reference's
    error           float  |value - reference_value| (error_kind "abs") or that / |reference_value| ("rel")
    tolerance       float  the bound on error
    passed          bool   error <= tolerance (None when skipped)
    wall_time_s     float  time spent computing value
    why             str    one line: why the tolerance is what it is (measured value, what it must catch)
    error_kind      str    "rel" | "abs"
    status          str    "passed" | "failed" | "skipped" | "error"
    check, topic    str    the check and its module (filled in by the runner)
    note            str    e.g. "NOT converged", the reason for a skip

Modules: ``record`` (Record, registry, Context), ``runner`` (select, run, print),
``report`` (JSON, Markdown, figures), ``references`` (stored reference data, regenerate-and-compare),
``common`` (meshes, linear solve, buckling); the checks by topic: ``strips``, ``cantilevers``,
``plates``, ``elements``, ``dynamics``, ``pedestal``.  The scripts in ``verification/`` print the
longer tables of the same computations; the stored reference data are the package ``reference``.
The command line is ``solidshell/verify_cli.py`` (the parser, and a call into this package).
"""

__all__ = ["CHECKS", "Record", "measure", "skipped", "select", "verify", "DEFAULT_OUT", "load_checks"]

TOPICS = ("strips", "cantilevers", "plates", "elements", "dynamics", "pedestal")
"""The topic modules; importing them registers their checks, in this (report) order."""

_FROM = {
    "CHECKS": "record",
    "Record": "record",
    "measure": "record",
    "skipped": "record",
    "DEFAULT_OUT": "runner",
    "select": "runner",
    "verify": "runner",
}


def load_checks() -> dict:
    """Import the topic modules (registering every check) and return the registry ``CHECKS``.

    Not done when the package is imported: ``solidshell verify --list`` or ``--references`` and
    the table scripts need only parts, and the topic modules pull in the element kernels, the explicit
    solver and scipy.sparse.linalg -- 1.2-1.6 s of a 20-element ``solidshell run`` (issue 13)."""
    import importlib

    for t in TOPICS:
        importlib.import_module(f"{__name__}.{t}")
    from .record import CHECKS

    return CHECKS


def __getattr__(name):
    # the registry and the runner's functions load every check on first use (PEP 562)
    if name in _FROM:
        import importlib

        load_checks()
        return getattr(importlib.import_module(f"{__name__}.{_FROM[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
