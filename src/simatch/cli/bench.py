"""``simatch bench``: measure the speeds the README reports (see `simatch.bench`)."""

from __future__ import annotations

import importlib
import json
import sys

from ..bench import BENCHMARKS
from . import UsageError


def add_parser(sub) -> None:
    p = sub.add_parser("bench", help="measure simulation speeds (real-time factors)",
                       description="Runs the benchmarks one after another in this process and prints their "
                                   "figures; with --json, one JSON object. Benchmarks: " + ", ".join(BENCHMARKS))
    p.add_argument("--json", action="store_true", help="print exactly one JSON object")
    p.add_argument("--only", action="append", default=[], metavar="NAME", help="run only this benchmark (repeatable)")
    p.add_argument("--seconds", type=float, metavar="S", help="simulated seconds per benchmark (default: each one's own)")
    p.set_defaults(func=main)


def main(args) -> int:
    names = args.only or list(BENCHMARKS)
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        raise UsageError(f"unknown benchmark(s) {', '.join(unknown)}; known: {', '.join(BENCHMARKS)}")
    out: dict = {}
    for name in names:
        module, _, func = BENCHMARKS[name].partition(":")
        if not args.json:
            print(f"running {name} ...", file=sys.stderr, flush=True)
        out.update(getattr(importlib.import_module(module), func)(args.seconds))
    if args.json:
        print(json.dumps(out))
    else:
        for key, value in out.items():
            print(f"{key:40s} {value}")
    return 0
