"""``simatch run ... --report FILE.html``: the run extension that writes the match report when the run ends,
from the live analysis of the run (`simatch.report.live`), with or without a recording. A run stopped by
Ctrl-C still gets its report, of what was played."""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

from ..errors import UsageError


class ReportExtension:
    def add_arguments(self, parser) -> None:
        group = parser.add_argument_group("report")
        group.add_argument(
            "--report",
            metavar="FILE.html",
            help="write the match report (plots of the score, events, possession, shots, heat maps, robots, "
            "roles) into one HTML file when the run ends",
        )

    def attach(self, sim, args):
        path = getattr(args, "report", None)
        if not path:
            return contextlib.nullcontext()
        out = Path(path)
        if out.suffix.lower() not in (".html", ".htm"):
            raise UsageError(f"--report {path}: a report is an HTML file: give a name ending in .html")
        if not out.parent.exists():
            raise UsageError(f"--report {path}: the folder {out.parent} does not exist")
        return _reporting(sim, out)


@contextlib.contextmanager
def _reporting(sim, path: Path):
    from .live import LiveAnalysis
    from .match_report import write_match_report

    live = LiveAnalysis.attach(sim)
    try:
        yield live
    finally:
        try:
            write_match_report(live.finish(sim.result()), path)
            print(f"simatch: wrote the match report {path}", file=sys.stderr)
        except OSError as exc:
            print(f"simatch: error: cannot write the report {path}: {exc}", file=sys.stderr)
