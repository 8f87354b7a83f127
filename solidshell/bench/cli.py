"""``solidshell bench [NAME ...] [--quick] [--out DIR] [--list]``."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from ..errors import InputError


def add_parser(sub) -> None:
    b = sub.add_parser(
        "bench",
        help="work-precision studies (error against wall time) and throughput; "
        "JSON, Markdown and log-log PNG per study",
    )
    b.add_argument("names", nargs="*", metavar="NAME", help="studies (default: all; --list names them)")
    b.add_argument("--quick", action="store_true", help="coarser meshes, fewer configurations (minutes)")
    b.add_argument("--out", metavar="DIR", default="bench", help="output folder (default: bench)")
    b.add_argument("--list", action="store_true", help="list the studies")


def run(args) -> int:
    from . import STUDIES
    from .workprec import run_study, write

    if args.list:
        for name, s in STUDIES.items():
            print(f"{name:12s} {s.title}")
        return 0
    unknown = [n for n in args.names if n not in STUDIES]
    if unknown:
        raise InputError(f"unknown bench study {', '.join(map(repr, unknown))}; known: {', '.join(STUDIES)}")
    names = args.names or list(STUDIES)
    out = Path(args.out)
    command = "solidshell bench " + " ".join(names) + (" --quick" if args.quick else "")
    for name in names:
        t = time.perf_counter()
        print(f"bench {name}{' (quick)' if args.quick else ''}:", flush=True)
        result = run_study(STUDIES[name], args.quick, say=lambda m: print(m, flush=True))
        paths = write(result, out, command)
        print(f"  {time.perf_counter() - t:.0f} s; wrote " + ", ".join(str(p) for p in paths), flush=True)
        sys.stdout.flush()
    return 0
