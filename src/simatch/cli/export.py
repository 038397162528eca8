"""``simatch export FILE.mcap --format parquet|csv [--out DIR]``: a recording as tidy tables for pandas,
polars or any tool that reads Parquet or CSV (see `simatch.record.tables` for the tables); ``--format
rosbag1 [--out FILE.bag]``: as a ROS 1 bag with the original Simatch's topics (`simatch.ros1.bag`); ``--format
rosbag2 [--out DIR]``: as a rosbag2 folder for ROS 2's bag tools (`simatch.record.rosbag2`)."""

from __future__ import annotations

import sys

from . import UsageError


def add_parser(sub) -> None:
    p = sub.add_parser(
        "export",
        help="write a recording's trajectories and events as Parquet or CSV tables",
        description="Writes tidy tables (one row per observation) of a recording: trajectories "
        "(one row per model per physics step), events, perception, commands, game "
        "commands and states, plus metadata.json.",
    )
    p.add_argument("file", metavar="FILE.mcap", help="a recording (simatch run --record)")
    p.add_argument(
        "--format",
        choices=("parquet", "csv", "rosbag1", "rosbag2"),
        default="parquet",
        help="table format (default parquet); rosbag1: a ROS 1 bag with the original Simatch's topics; "
        "rosbag2: a folder with the MCAP file and metadata.yaml",
    )
    p.add_argument(
        "--out",
        metavar="DIR|FILE",
        help="folder for the tables (default: FILE_tables next to the recording); for rosbag1 the bag's path "
        "(default: FILE.bag next to the recording); for rosbag2 the folder (default: FILE without .mcap)",
    )
    p.set_defaults(func=main)


def main(args) -> int:
    if args.format == "rosbag1":
        return _rosbag1(args)
    if args.format == "rosbag2":
        return rosbag2_folder(args)
    from ..record.reader import RecordingError
    from ..record.tables import ExportError, export

    try:
        folder, counts, rec = export(args.file, args.format, args.out)
    except (ExportError, RecordingError) as exc:
        raise UsageError(str(exc)) from None
    for text in rec.problems:
        print(f"simatch: warning: {text}", file=sys.stderr)
    print(f"wrote {len(counts)} tables to {folder}/ (and metadata.json):")
    width = max((len(name) for name in counts), default=0) + len(args.format) + 1
    for name, rows in sorted(counts.items()):
        print(f"  {f'{name}.{args.format}':{width}s} {rows:>9} rows")
    return 0


def _rosbag1(args) -> int:
    from ..record.reader import RecordingError
    from ..ros1.bag import BagError, export_rosbag1

    try:
        bag, counts, rec = export_rosbag1(args.file, args.out)
    except (BagError, RecordingError) as exc:
        raise UsageError(str(exc)) from None
    for text in rec.problems:
        print(f"simatch: warning: {text}", file=sys.stderr)
    print(f"wrote {bag}: {sum(counts.values())} messages on {len(counts)} topics (rosbag info {bag.name})")
    return 0


def rosbag2_folder(args) -> int:
    from ..record.rosbag2 import METADATA, Rosbag2Error, export

    try:
        folder = export(args.file, args.out)
    except Rosbag2Error as exc:
        raise UsageError(str(exc)) from None
    print(f"wrote the rosbag2 folder {folder}/ ({METADATA} and the recording)")
    return 0
