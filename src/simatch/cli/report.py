"""``simatch report FILE.mcap -o report.html``: a recorded match as one HTML page of plots (docs/report.md)."""

from __future__ import annotations

import sys
from pathlib import Path

from . import UsageError


def add_parser(sub) -> None:
    p = sub.add_parser(
        "report",
        help="write a recorded match's report: one HTML file of plots that opens with no network",
        description="Reads a recording (simatch run --record) and writes one self-contained HTML page: the score "
        "and event timeline with the referee's reasons, possession over time, the shots on the field, heat maps "
        "of the ball and of each team, distance and top speed per robot, role time, the game stages.",
    )
    p.add_argument("file", metavar="FILE.mcap|DIR", help="a recording (or a rosbag2 folder of --record DIR/)")
    p.add_argument(
        "-o",
        "--out",
        metavar="REPORT.html",
        help="where to write it (default: FILE.html beside FILE or DIR.html beside DIR)",
    )
    p.add_argument("--force", action="store_true", help="overwrite an existing report")
    p.set_defaults(func=main)


def main(args) -> int:
    from ..record import rosbag2
    from ..record.reader import RecordingError
    from ..report.match_report import write_match_report
    from ..report.recorded import analyse_recording

    src = Path(args.file)
    out = Path(args.out) if args.out else rosbag2.beside(src, ".html")
    if out.suffix.lower() not in (".html", ".htm"):
        raise UsageError(f"{out}: a report is an HTML file: give a name ending in .html")
    if out.exists() and not args.force:
        raise UsageError(f"{out} exists: give another name with -o, or --force to overwrite it")
    try:
        stats, rec = analyse_recording(src)
    except RecordingError as exc:
        raise UsageError(str(exc)) from None
    if not rec.is_simatch:
        raise UsageError(f"{src} is an MCAP file but not a simatch recording (no simatch metadata)")
    for text in rec.problems:
        print(f"simatch: warning: {text}", file=sys.stderr)
    try:
        write_match_report(stats, out)
    except OSError as exc:
        raise UsageError(f"cannot write {out}: {exc}") from None
    score = stats["score_timeline"][-1]["score"]
    print(
        f"wrote {out}: {' - '.join(f'{t} {g}' for t, g in score.items())}, {len(stats['shots'])} shots, "
        f"{stats['duration']:.1f} s"
    )
    return 0
