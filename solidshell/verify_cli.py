"""The ``solidshell verify`` subcommand: its parser, and a call into the package ``verification``
(the checks, ``verification.checks``; the stored references, the package ``reference``), imported
only when the command runs -- the parser is built on every solidshell command."""

from __future__ import annotations

EXIT_OK, EXIT_FAILED = 0, 1


def add_parser(sub) -> None:
    v = sub.add_parser("verify", help="run the verification checks against independent references")
    v.add_argument("names", nargs="*", metavar="NAME", help="checks to run (default: the default set; --list)")
    v.add_argument("--quick", action="store_true", help="the reduced set (< 2 min), part of the test run")
    v.add_argument("--out", metavar="DIR", help="output folder (default: verification-out)")
    v.add_argument("--list", action="store_true", help="list the checks and exit")
    v.add_argument(
        "--references",
        action="store_true",
        help="regenerate every stored reference file and check that it has not changed",
    )
    v.add_argument(
        "--fenicsx", action="store_true", help="run the DOLFINx cross-check (verification/fenicsx; needs dolfinx)"
    )
    v.add_argument(
        "--reuse",
        action="store_true",
        help="with --fenicsx: reuse the converged DOLFINx results of identical jobs in OUT/fenicsx_work",
    )


def run(args) -> int:
    """The command; bad input raises InputError (exit 2, one line: solidshell.cli.main)."""
    from verification import checks
    from verification.checks import runner

    out_dir = args.out or runner.DEFAULT_OUT
    if args.list:
        sel = checks.select(args.names) if args.names else list(checks.load_checks().values())
        w = max(len(c.name) for c in sel)
        for c in sel:
            sets = "quick+default" if c.quick and c.default else "default" if c.default else "by name"
            print(f"{c.name:<{w}}  {sets:<13}  {c.summary}")
        return EXIT_OK
    if args.references:
        from verification.checks.references import check_references

        rows = check_references(quick=args.quick)
        return EXIT_FAILED if any(r["passed"] is False for r in rows) else EXIT_OK
    if args.fenicsx:
        res = runner.fenicsx(out_dir, reuse=args.reuse)
    else:
        res = checks.verify(args.names or None, quick=args.quick, out_dir=out_dir)
    return EXIT_FAILED if res["failed"] else EXIT_OK
