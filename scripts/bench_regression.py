#!/usr/bin/env python3
"""Compare this tree's speed with the figures kept in docs/performance.md ("Reference figures"), and say
by how much each one moved. Not part of CI (speed is measured, never asserted by the tests): run it
before and after a change that may cost time, on a machine as quiet as the one the figures were taken on.

Each reference row names a figure of ``simatch bench --json``, the benchmark that gives it, its value,
and whether higher or lower is better. The script runs each benchmark needed (``simatch bench --only NAME
--json``, each in a fresh process, ``--runs`` times, taking the median of each figure), or reads the
figures from JSON files of earlier ``simatch bench --json`` runs (``--from``), and prints one line per
figure: reference, measured, the change in percent, and "worse" when it is worse than the reference by
more than ``--tolerance`` percent. The exit status is 1 if any figure is worse, else 0.

    python scripts/bench_regression.py                       # the match and physics figures, once each
    python scripts/bench_regression.py --runs 3 --tolerance 8
    python scripts/bench_regression.py --from before.json --json
    python scripts/bench_regression.py --only match_cpu_rtf --only physics_cpu_rtf

On a machine shared with other work the wall-clock figures (``*_rtf``) move by tens of percent; the
CPU-time ones (``*_cpu_rtf``) and the ratios of one run (``match_physics_cpu_ratio``) move less.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path

from simatch.cli.bench import ratios

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "performance.md"
HEADING = "## Reference figures"
#: a row of the reference table: | `figure` | bench(es) | value | higher/lower | ... | (a figure of two
#: benchmarks of one run, a ratio, names both: physics+match)
ROW = re.compile(
    r"^\|\s*`(?P<figure>[a-z0-9_]+)`\s*\|\s*(?P<bench>[a-z0-9_+]+)\s*\|\s*(?P<value>[-+0-9.eE]+)\s*\|"
    r"\s*(?P<better>higher|lower)\s*\|"
)


def references(doc: Path = DOC) -> list[dict]:
    """The rows of the reference table of ``doc`` (figure, bench, value, better), in their order."""
    text = doc.read_text(encoding="utf-8")
    start = text.find(HEADING)
    if start < 0:
        raise SystemExit(f"{doc}: no section {HEADING!r}")
    rows = []
    for line in text[start + len(HEADING) :].splitlines():
        if line.startswith("## "):
            break
        m = ROW.match(line.strip())
        if m:
            rows.append({**m.groupdict(), "value": float(m["value"])})
    if not rows:
        raise SystemExit(f"{doc}: the section {HEADING!r} has no rows like | `figure` | bench | value | higher |")
    return rows


def run_bench(bench: str, seconds: float | None) -> dict:
    cmd = [sys.executable, "-m", "simatch", "bench", "--only", bench, "--json"]
    if seconds is not None:
        cmd += ["--seconds", repr(seconds)]
    print(f"running {' '.join(cmd[2:])} ...", file=sys.stderr, flush=True)
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if proc.returncode != 0:
        raise SystemExit(f"benchmark {bench} failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def measure(rows: list[dict], runs: int, seconds: float | None) -> dict[str, float]:
    """The median over ``runs`` of every figure of ``rows``, each benchmark run once per round; the
    ratios of physics and match come from the same round's two runs."""
    benches = list(dict.fromkeys(b for r in rows for b in r["bench"].split("+")))
    values: dict[str, list[float]] = {}
    for _ in range(runs):
        out: dict = {}
        for bench in benches:
            out.update(run_bench(bench, seconds))
        out.update(ratios(out))
        for key, value in out.items():
            if isinstance(value, int | float) and not isinstance(value, bool):
                values.setdefault(key, []).append(float(value))
    return {key: statistics.median(v) for key, v in values.items()}


def compare(rows: list[dict], measured: dict[str, float], tolerance: float) -> list[dict]:
    """One verdict per row: the change in percent (positive: better) and whether it is worse than the
    reference by more than ``tolerance`` percent."""
    out = []
    for r in rows:
        got = measured.get(r["figure"])
        line = {"figure": r["figure"], "reference": r["value"], "measured": got, "better": r["better"]}
        if got is None:
            line.update(change_pct=None, verdict="missing")
        else:
            change = (got - r["value"]) / abs(r["value"]) * 100.0 if r["value"] else 0.0
            if r["better"] == "lower":
                change = -change
            line.update(change_pct=round(change, 1), verdict="worse" if change < -tolerance else "ok")
        out.append(line)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--only", action="append", default=[], metavar="FIGURE", help="check only this figure (repeatable)")
    ap.add_argument("--runs", type=int, default=1, help="rounds of benchmarks; the median of each figure counts")
    ap.add_argument("--seconds", type=float, help="simulated seconds per benchmark (default: each one's own)")
    ap.add_argument("--tolerance", type=float, default=10.0, help="percent worse than the reference that still passes")
    ap.add_argument(
        "--from",
        dest="files",
        action="append",
        default=[],
        metavar="JSON",
        help="figures from this `simatch bench --json` output instead of running (repeatable)",
    )
    ap.add_argument("--doc", type=Path, default=DOC, help="the file holding the reference table")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)
    if args.runs < 1 or not args.tolerance >= 0:
        ap.error("--runs must be at least 1 and --tolerance not negative")
    rows = references(args.doc)
    if args.only:
        unknown = set(args.only) - {r["figure"] for r in rows}
        if unknown:
            ap.error(f"no reference for {', '.join(sorted(unknown))}; known: {', '.join(r['figure'] for r in rows)}")
        rows = [r for r in rows if r["figure"] in args.only]
    if args.files:
        measured: dict[str, float] = {}
        for name in args.files:
            try:
                data = json.loads(Path(name).read_text(encoding="utf-8").strip().splitlines()[-1])
            except (OSError, ValueError, IndexError) as exc:
                ap.error(f"{name}: not the JSON of simatch bench --json ({exc})")
            data.update(ratios(data))
            measured.update({k: float(v) for k, v in data.items() if isinstance(v, int | float)})
    else:
        measured = measure(rows, args.runs, args.seconds)
    verdicts = compare(rows, measured, args.tolerance)
    worse = [v for v in verdicts if v["verdict"] == "worse"]
    if args.json:
        print(json.dumps({"load": round(os.getloadavg()[0], 2), "tolerance_pct": args.tolerance, "figures": verdicts}))
    else:
        head = f"{'figure':28s} {'reference':>10s} {'measured':>10s} {'change':>8s}"
        print(f"{head}  verdict (tolerance {args.tolerance:g} %)")
        for v in verdicts:
            got = "-" if v["measured"] is None else f"{v['measured']:g}"
            change = "-" if v["change_pct"] is None else f"{v['change_pct']:+.1f}%"
            print(f"{v['figure']:28s} {v['reference']:>10g} {got:>10s} {change:>8s}  {v['verdict']}")
        print(f"load average {os.getloadavg()[0]:.2f}; positive change is better")
    return 1 if worse else 0


if __name__ == "__main__":
    sys.exit(main())
