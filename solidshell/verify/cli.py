"""The ``solidshell verify`` subcommand (parser and command), kept out of solidshell/cli.py."""

from __future__ import annotations

import sys
from pathlib import Path

EXIT_OK, EXIT_FAILED, EXIT_INPUT = 0, 1, 2


def add_parser(sub) -> None:
    v = sub.add_parser("verify", help="run the verification checks against independent references")
    v.add_argument("names", nargs="*", metavar="NAME", help="checks to run (default: the default set; --list)")
    v.add_argument("--quick", action="store_true", help="the reduced set (< 2 min), part of the test run")
    v.add_argument("--out", metavar="DIR", help="output folder (default: verification-out)")
    v.add_argument("--list", action="store_true", help="list the checks and exit")
    v.add_argument("--references", action="store_true",
                   help="regenerate every stored reference file and check that it has not changed")
    v.add_argument("--fenicsx", action="store_true",
                   help="run the DOLFINx cross-check (verification/fenicsx; needs dolfinx)")
    v.add_argument("--reuse", action="store_true",
                   help="with --fenicsx: reuse the converged DOLFINx results of identical jobs in OUT/fenicsx_work")


def _say(msg: str) -> None:
    print(" ".join(str(msg).split()), file=sys.stderr)


def _fenicsx(out_dir, reuse: bool = False) -> int:
    """verification.fenicsx.crosscheck.main(out_dir) -> list of record dicts (solidshell.verify
    record format); printed like the other checks and written to <out>/fenicsx.json."""
    import dataclasses
    import importlib
    import json

    from ..errors import InputError, IOFailure
    from .record import Record
    from .runner import HEADER, line, prepare_out

    root = Path(__file__).resolve().parents[2]
    if (root / "verification").is_dir() and str(root) not in sys.path:
        sys.path.insert(0, str(root))
    try:   # DOLFINx runs under the system python (verification/fenicsx/jobs.py), not in this process
        mod = importlib.import_module("verification.fenicsx.crosscheck")
        jobs = importlib.import_module("verification.fenicsx.jobs")
    except ImportError as e:
        _say(f"solidshell: error: --fenicsx needs verification/fenicsx/ from a source checkout: {e}")
        return EXIT_INPUT
    try:
        jobs.check_dolfinx()                     # before anything is written
    except jobs.DolfinxMissing as e:
        _say(f"solidshell: error: {e}")
        return EXIT_INPUT
    out = prepare_out(out_dir)
    try:
        rows = mod.main(out, reuse=reuse)
    except jobs.DolfinxMissing as e:
        _say(f"solidshell: error: {e}")
        return EXIT_INPUT
    fields = set(Record.__dataclass_fields__)
    required = {k for k, f in Record.__dataclass_fields__.items() if f.default is dataclasses.MISSING}
    recs = []
    for i, r in enumerate(rows):
        missing = sorted(required - set(r))
        if missing:
            raise InputError(f"verification.fenicsx.crosscheck record {i} lacks {', '.join(missing)}")
        r = {k: v for k, v in r.items() if k in fields}
        if "status" not in r:
            r["status"] = "skipped" if r["passed"] is None else "passed" if r["passed"] else "failed"
        recs.append(Record(**r))
    print(HEADER)
    for r in recs:
        print(line(r))
    p = out / "fenicsx.json"
    try:
        p.write_text(json.dumps([r.to_dict() for r in recs], indent=1, default=float))
    except OSError as e:
        raise IOFailure.from_oserror(e, p) from None
    print(f"wrote {p}")
    return EXIT_FAILED if any(r.status in ("failed", "error") or r.passed is False for r in recs) else EXIT_OK


def run(args) -> int:
    from . import CHECKS, DEFAULT_OUT, select, verify

    out_dir = args.out or DEFAULT_OUT
    if args.list:
        checks = select(args.names) if args.names else list(CHECKS.values())
        w = max(len(c.name) for c in checks)
        for c in checks:
            sets = "quick+default" if c.quick and c.default else "default" if c.default else "by name"
            print(f"{c.name:<{w}}  {sets:<13}  {c.summary}")
        return EXIT_OK
    if args.references:
        from .references import check_references

        rows = check_references(quick=args.quick)
        return EXIT_FAILED if any(r["passed"] is False for r in rows) else EXIT_OK
    if args.fenicsx:
        return _fenicsx(out_dir, reuse=args.reuse)
    res = verify(args.names or None, quick=args.quick, out_dir=out_dir)
    return EXIT_FAILED if res["failed"] else EXIT_OK
