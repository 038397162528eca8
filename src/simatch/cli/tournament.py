"""``simatch tournament --teams A,B,C --seeds N``: play every pairing over N seeds with both colours on Ray,
store each result as it comes back, print the standing (docs/tournament.md).

The same command run again plays only what is missing: after Ctrl-C, a killed worker or a killed driver,
or with more seeds or teams.
"""

from __future__ import annotations

import contextlib
import json
import signal
import sys

from . import UsageError
from .run import add_overrides_option, overrides_of


def add_parser(sub) -> None:
    p = sub.add_parser(
        "tournament",
        help="play a round robin, league or knockout of teams on Ray and print the standing",
        description="Plays every pairing of the teams over the seeds with both colours, each match refereed "
        "and deterministic by its seed, as Ray tasks (a local Ray instance on every core, or a cluster with "
        "--address). Each result is stored as it comes back (OUT/matches/, Parquet), so the same command "
        "resumes an interrupted tournament and plays only what is missing. Prints the standing (points, goal "
        "difference, Elo with a 95% interval from the seeds); with --json, one JSON object.",
    )
    p.add_argument(
        "--teams",
        action="append",
        required=True,
        metavar="A,B,...",
        help="the teams: shipped strategies (nubot, simple), plug-in classes (package.module:Class, importable "
        "here: PYTHONPATH), scenes' teams (path/scene.toml:cyan); NAME=TEAM names one in the standing",
    )
    p.add_argument("--seeds", type=int, default=10, metavar="N", help="seeds per pairing and colour (default 10)")
    p.add_argument("--first-seed", type=int, default=0, metavar="K", help="seeds K .. K+N-1 (default 0)")
    p.add_argument("--scene", default="msl_5v5", help="the scene the matches are played in (default msl_5v5)")
    add_overrides_option(p, "override a scene value for every match, e.g. match.half_duration=300")
    p.add_argument("--format", default="round-robin", choices=("round-robin", "league", "knockout"))
    p.add_argument(
        "--out",
        default="tournament",
        metavar="DIR",
        help="results folder (default ./tournament): one Parquet row per match as it ends, the whole table, "
        "standing.json; several tournaments may share it",
    )
    p.add_argument("--record", metavar="DIR", help="keep each match's MCAP recording in DIR")
    p.add_argument("--report", metavar="DIR", help="write the tournament's and every match's HTML report in DIR")
    p.add_argument(
        "--address",
        metavar="ADDR",
        help="an existing Ray cluster (host:port); default: a local Ray instance on every core (or the cluster of "
        "'ray job submit', RAY_ADDRESS)",
    )
    p.add_argument("--workers", type=int, metavar="N", help="matches at once (default: every CPU of the cluster)")
    p.add_argument("--no-ray", action="store_true", help="play the matches one by one in this process, without Ray")
    p.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="wall-clock limit per match in seconds (default: the match's simulated length + 120 s)",
    )
    p.add_argument(
        "--retry-failed", action="store_true", help="play again the matches recorded as failed (error, timeout)"
    )
    p.add_argument("--json", action="store_true", help="print exactly one JSON object: the standing and the counts")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=main)


class _Terminated(KeyboardInterrupt):
    """SIGTERM, stopping the driver the way Ctrl-C does."""


_TERMINATED: list[bool] = []  # set by the SIGTERM handler (Ray's code may re-raise a plain KeyboardInterrupt)


@contextlib.contextmanager
def _sigterm_as_interrupt():
    def handler(signum, frame):
        _TERMINATED.append(True)
        raise _Terminated()

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


class _Bar:
    def __init__(self, enabled: bool, played: int, expected: int):
        self.bar = None
        if enabled and sys.stderr.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=expected, initial=played, unit="match", file=sys.stderr, dynamic_ncols=True)
        self.failed = 0

    def __call__(self, row: dict, played: int, expected: int) -> None:
        if row["status"] != "ok":
            self.failed += 1
            print(
                f"simatch: match {row['home']} vs {row['away']} seed {row['seed']} {row['status']}: {row.get('error')}",
                file=sys.stderr,
            )
        if self.bar is not None:
            if expected != self.bar.total:
                self.bar.total = expected
            text = (
                f"{row['home']} {row['home_goals']}-{row['away_goals']} {row['away']} (seed {row['seed']})"
                if row["status"] == "ok"
                else f"{row['home']} vs {row['away']}: {row['status']}"
            )
            self.bar.set_postfix_str(text + (f", {self.failed} failed" if self.failed else ""), refresh=False)
            self.bar.n = played
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def print_standing(summary: dict, file=sys.stdout) -> None:
    t = summary["tournament"]
    m = summary["matches"]
    print(
        f"{t['format']} of {len(t['teams'])} teams, scene {t['scene']}, {len(t['seeds'])} seed(s) with both "
        f"colours: {m['played']} played, {m['failed']} failed"
        + ("" if summary["complete"] else f", {m['missing']} still to play"),
        file=file,
    )
    head = (
        f"{'#':>2}  {'team':24s} {'P':>4} {'W':>4} {'D':>4} {'L':>4} {'goals':>9} {'diff':>5} {'pts':>5}  "
        f"{'Elo':>5} {'95% interval':>14}"
    )
    print(head, file=file)
    for s in summary["standing"]:
        goals = f"{s['goals_for']}:{s['goals_against']}"
        print(
            f"{s['rank']:>2}  {s['team'][:24]:24s} {s['played']:>4} {s['won']:>4} {s['drawn']:>4} {s['lost']:>4} "
            f"{goals:>9} {s['goal_difference']:>+5d} {s['points']:>5}  {s['elo']:>5.0f} "
            f"{s['elo_low']:>6.0f}..{s['elo_high']:<6.0f}" + (f"  ({s['failed']} failed)" if s["failed"] else ""),
            file=file,
        )
    detail = summary.get("format_detail") or {}
    if detail.get("champion"):
        print(f"champion: {detail['champion']}", file=file)
    for f in summary["failed"]:
        print(f"failed: {f['home']} vs {f['away']} seed {f['seed']} ({f['status']}): {f['error']}", file=file)
    print(
        f"results: {summary['results']}" + (f"   report: {summary['report']}" if summary.get("report") else ""),
        file=file,
    )


def main(args) -> int:
    from ..tournament.entries import parse_entries
    from ..tournament.runner import PlainLoop, RayPool, plugin_paths
    from ..tournament.tournament import Tournament

    if args.seeds < 1:
        raise UsageError("--seeds must be at least 1")
    entries = parse_entries(args.teams)
    tournament = Tournament(
        entries,
        seeds=range(args.first_seed, args.first_seed + args.seeds),
        out=args.out,
        scene=args.scene,
        overrides=overrides_of(args),
        format=args.format,
        timeout=args.timeout,
        record=args.record,
        report=args.report,
        retry_failed=args.retry_failed,
    )
    done = tournament.results()
    played, expected = tournament.played(done), tournament.format.expected(done)
    missing = len(tournament.format.wave(done))
    executor = None
    bar = None
    try:
        if missing:
            if args.no_ray:
                executor = PlainLoop()
            else:
                if not args.json:
                    print("simatch: starting Ray ...", file=sys.stderr, flush=True)
                modules = [e.strategy.partition(":")[0] for e in entries if ":" in e.strategy]
                executor = RayPool(args.address, args.workers, plugin_paths(modules))
            if not args.json:
                print(
                    f"simatch: {missing} match(es) to play ({played} of {expected} played before), "
                    f"{executor.description}; results in {tournament.store.folder}/",
                    file=sys.stderr,
                    flush=True,
                )
            bar = _Bar(not args.quiet and not args.json, played, expected)
            # after Ray's start: its core installs a SIGTERM handler of its own (a stack dump, then abort)
            with _sigterm_as_interrupt():
                summary = tournament.play(executor, on_result=bar)
        else:
            summary = tournament.finish(done)
    except KeyboardInterrupt as exc:
        if bar is not None:
            bar.close()
        with _sigterm_as_interrupt():
            summary = tournament.finish()
        m = summary["matches"]
        print(
            f"simatch: interrupted with {m['played'] + m['failed']} match(es) played and {m['missing']} to "
            f"play: run the same command to play the rest",
            file=sys.stderr,
        )
        _print(summary, args.json)
        return 143 if isinstance(exc, _Terminated) or _TERMINATED else 130
    finally:
        if bar is not None:
            bar.close()
        if executor is not None:
            executor.close()
    _print(summary, args.json)
    return 0


def _print(summary: dict, as_json: bool) -> None:
    if as_json:
        print(json.dumps(summary))
    else:
        print_standing(summary)
