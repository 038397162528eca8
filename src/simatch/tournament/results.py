"""A tournament's results on disk, appended match by match so that nothing played is ever lost.

    OUT/matches/<match_id>.parquet        one row per finished match (written atomically as it ends)
    OUT/matches/<match_id>.analysis.json.gz   the match's analysis (for its report, written before the row)
    OUT/matches.parquet                   every row of the tournament in schedule order (rewritten at the end
                                          of every run of the command, also an interrupted one)
    OUT/standing.json                     the standing as ``--json`` prints it

A row file appears whole or not at all (written beside and renamed), so a driver killed at any moment leaves
only whole rows; the next run of the same command reads them and plays only what is missing. The folder
``OUT/matches`` is itself a Parquet dataset (``pandas.read_parquet("OUT/matches")``); ``matches.parquet``
is the same rows in one file.
"""

from __future__ import annotations

import gzip
import json
import logging
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import UsageError
from ..report.files import write_atomic

log = logging.getLogger(__name__)

#: statuses of a finished match: "ok"; "error" (the match raised: a plug-in or scene error), "timeout" (it ran
#: longer than the limit: a plug-in looping), "crashed" (the process playing it died, twice)
FAILED = ("error", "timeout", "crashed")
#: failures replayed by the next run of the command without being asked (a killed worker is no verdict)
REPLAYED = ("crashed",)

_INT = pa.int32()
_F = pa.float64()
_S = pa.string()
SCHEMA = pa.schema(
    [
        ("match_id", _S),
        ("order", pa.int64()),
        ("stage", _S),
        ("tie", _S),
        ("seed", pa.int64()),
        ("home", _S),
        ("away", _S),
        ("home_colour", _S),
        ("away_colour", _S),
        ("home_strategy", _S),
        ("away_strategy", _S),
        ("status", _S),
        ("error", _S),
        ("home_goals", _INT),
        ("away_goals", _INT),
        ("winner", _S),  # the winner's name ("" for a draw or a failed match)
        ("winner_colour", _S),
        ("home_fouls", _INT),
        ("away_fouls", _INT),
        ("home_yellow_cards", _INT),
        ("away_yellow_cards", _INT),
        ("home_red_cards", _INT),
        ("away_red_cards", _INT),
        ("home_possession", _F),
        ("away_possession", _F),
        ("home_shots", _INT),
        ("away_shots", _INT),
        ("home_on_target", _INT),
        ("away_on_target", _INT),
        ("home_strategy_errors", _INT),
        ("away_strategy_errors", _INT),
        ("sim_seconds", _F),
        ("wall_seconds", _F),
        ("state_digest", _S),
        ("worker", _S),
        ("recording", _S),
        ("simatch_version", _S),
        ("finished_at", _S),
    ]
)
COLUMNS = [f.name for f in SCHEMA]


class ResultStore:
    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        self.rows_dir = self.folder / "matches"

    def prepare(self) -> None:
        """Create the folder; drop what a killed run left half-written (never a whole row)."""
        try:
            self.rows_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UsageError(f"cannot create the results folder {self.rows_dir}: {exc}") from None
        for stale in [*self.rows_dir.glob(".*.tmp"), *self.folder.glob(".*.tmp")]:
            stale.unlink(missing_ok=True)

    def load(self) -> tuple[dict[str, dict], list[str]]:
        """Every whole row in the folder (match id -> row) and what could not be read (those are replayed)."""
        rows: dict[str, dict] = {}
        problems: list[str] = []
        if not self.rows_dir.is_dir():
            return rows, problems
        for path in sorted(self.rows_dir.glob("*.parquet")):
            try:
                table = pq.read_table(path)
                for row in table.to_pylist():
                    rows[row["match_id"]] = {c: row.get(c) for c in COLUMNS}
            except Exception as exc:  # a damaged file: say so, play the match again
                problems.append(f"{path.name}: {type(exc).__name__}: {exc}")
        return rows, problems

    def add(self, row: dict, analysis: dict | None = None) -> None:
        """Keep a finished match: its analysis first, then its row (the row marks the match as played)."""
        if analysis is not None:
            data = gzip.compress(json.dumps(analysis, separators=(",", ":")).encode(), compresslevel=6)
            write_atomic(self.rows_dir / f"{row['match_id']}.analysis.json.gz", data)
        table = pa.Table.from_pylist([{c: row.get(c) for c in COLUMNS}], schema=SCHEMA)
        _atomic_table(self.rows_dir / f"{row['match_id']}.parquet", table)

    def analysis(self, match_id: str) -> dict | None:
        path = self.rows_dir / f"{match_id}.analysis.json.gz"
        try:
            return json.loads(gzip.decompress(path.read_bytes()))
        except FileNotFoundError:
            return None
        except (OSError, ValueError, EOFError) as exc:
            log.warning("analysis of match %s cannot be read: %s", match_id, exc)
            return None

    def write_table(self, rows: list[dict]) -> Path:
        """All rows of the tournament, in schedule order, as one Parquet file."""
        path = self.folder / "matches.parquet"
        table = pa.Table.from_pylist([{c: r.get(c) for c in COLUMNS} for r in rows], schema=SCHEMA)
        _atomic_table(path, table)
        return path

    def write_json(self, name: str, data: dict) -> Path:
        path = self.folder / name
        write_atomic(path, (json.dumps(data, indent=1, default=str) + "\n").encode())
        return path


def _atomic_table(path: Path, table: pa.Table) -> None:
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    write_atomic(path, sink.getvalue().to_pybytes())
