"""``simatch recover FILE.mcap [-o OUT.mcap]``: a finalised, indexed MCAP file of everything intact in a
recording that was never finalised or is damaged (see `simatch.record.recover`), so that every MCAP tool
reads it whole. Without ``-o`` the file is replaced, atomically, if it needs it."""

from __future__ import annotations

import json
import sys

from . import UsageError


def add_parser(sub) -> None:
    p = sub.add_parser(
        "recover",
        help="finalise and index a recording that was cut off or damaged",
        description="Reads a recording from its start, keeps every intact record (metadata, schemas, channels, "
        "every chunk whose checksum holds) and writes a finalised, indexed MCAP file that every MCAP reader reads "
        "whole. A recording whose recording process was killed is finalised by its writer process already; "
        "this is for a file whose writer process stopped too (or was damaged on disk). Without -o the file is "
        "replaced (written next to it, then renamed), only if it needs it.",
    )
    p.add_argument(
        "file",
        metavar="FILE.mcap|DIR",
        help="the recording to recover (a rosbag2 folder of --record DIR/: its file, and its metadata.yaml written)",
    )
    p.add_argument("-o", "--output", metavar="OUT.mcap", help="write the recovered file here (never overwritten)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=main)


def main(args) -> int:
    from ..record.recover import RecoverError, recover

    bar = None
    if not args.quiet and not args.json and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=100, unit="%", file=sys.stderr, dynamic_ncols=True, desc="reading")

    def progress(fraction: float) -> None:
        if bar is not None:
            bar.update(round(100 * fraction) - bar.n)

    try:
        report = recover(args.file, args.output, progress=progress)
    except RecoverError as exc:
        raise UsageError(str(exc)) from None
    except OSError as exc:
        raise UsageError(f"cannot recover {args.file}: {exc.strerror or exc}") from None
    finally:
        if bar is not None:
            bar.close()
    print(json.dumps(report.as_dict()) if args.json else report.describe())
    return 0
