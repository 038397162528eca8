"""The exported tables a data scientist opens: one null for every empty value, lists as lists (of structs for a
list of messages, and valid JSON in CSV), every documented table written (empty ones too), the docs' table list
equal to what export writes."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
import pytest

import simatch
from simatch.record import Recorder, export
from simatch.record.tables import ALWAYS

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def refereed(tmp_path_factory):
    """A refereed match recorded from the start, nobody intervening: no operator commands at all."""
    path = tmp_path_factory.mktemp("refereed") / "match.mcap"
    with simatch.Simulation("msl_5v5", seed=2) as sim, Recorder.for_run(sim, path, command_line=["pytest"]):
        sim.run(seconds=12.0)
    return path


@pytest.fixture(scope="module")
def tables(refereed, tmp_path_factory):
    out = {}
    for fmt in ("parquet", "csv"):
        folder, counts, _ = export(refereed, fmt, tmp_path_factory.mktemp(fmt))
        out[fmt] = (folder, counts)
    return out


def _read(folder: Path, name: str, fmt: str) -> pa.Table:
    path = folder / f"{name}.{fmt}"
    if fmt == "parquet":
        return pq.read_table(path)
    return pacsv.read_csv(path, convert_options=pacsv.ConvertOptions(strings_can_be_null=True))


def test_every_documented_table_is_written_even_when_empty(tables):
    for fmt, (folder, counts) in tables.items():
        assert set(ALWAYS) <= set(counts), set(ALWAYS) - set(counts)
        assert counts["operator_command"] == 0
        ops = _read(folder, "operator_command", fmt)
        assert ops.num_rows == 0 and {"t", "stamp", "step", "call", "target", "args"} <= set(ops.column_names)
        assert counts["trajectories"] > 0 and counts["events"] > 0 and counts["game_state"] > 0


def test_an_empty_value_is_null_in_every_table(tables):
    folder, counts = tables["parquet"]
    for name in counts:
        table = pq.read_table(folder / f"{name}.parquet")
        for field in table.schema:
            values = table.column(field.name).to_pylist()
            if pa.types.is_string(field.type):
                assert "" not in values, f"{name}.{field.name} holds empty strings"
            if pa.types.is_floating(field.type):
                assert not any(v is not None and math.isnan(v) for v in values), f"{name}.{field.name} holds NaN"
    events = pq.read_table(folder / "events.parquet").to_pylist()
    assert events and all(e["robot"] is None or e["robot"] >= 1 for e in events)
    # as in `simatch run --json`: a stage change concerns no team, no robot, no place
    stage = next(e for e in events if e["type"] == "stage")
    assert stage["team"] is None and stage["robot"] is None and stage["x"] is None and stage["y"] is None
    placed = next(e for e in events if e["type"] == "ball_placed")
    assert placed["team"] == "cyan" and placed["detail"].startswith("ball placed for the kick-off")
    # a robot with no target has none (the message's NaN), the ball belongs to no team
    strat = pq.read_table(folder / "strategy_info.parquet")
    assert strat.column("target_x").null_count > 0
    traj = pq.read_table(folder / "trajectories.parquet").to_pylist()
    ball = next(r for r in traj if r["model"] == "ball")
    assert ball["team"] is None and ball["robot"] is None


def test_a_list_of_messages_is_a_list_column_and_valid_json_in_csv(tables):
    folder, _ = tables["parquet"]
    team = pq.read_table(folder / "team_strategy.parquet")
    typ = team.schema.field("strategies").type
    assert pa.types.is_list(typ) and pa.types.is_struct(typ.value_type)
    rows = team.to_pylist()
    full = next(r for r in rows if len(r["strategies"]) == 5)
    first = full["strategies"][0]
    assert {"agent_id", "role", "target_x", "pass_cmd_catch_x", "user"} <= set(first)
    # the same as the robot's own StrategyInfo at that tick
    info = pq.read_table(folder / "strategy_info.parquet").to_pylist()
    own = next(
        r for r in info if r["team"] == full["team"] and r["tick"] == first["tick"] and r["robot"] == first["agent_id"]
    )
    for key in ("role", "action", "target_x", "target_y", "pass_cmd_catch_x"):
        assert own[key] == first[key], key
    # CSV: JSON text that strict JSON readers take (no NaN)
    csv_folder, _ = tables["csv"]
    text = _read(csv_folder, "team_strategy", "csv").column("strategies").to_pylist()

    def strict(token):
        raise ValueError(f"not JSON: {token}")

    parsed = [json.loads(v, parse_constant=strict) for v in text]
    assert [len(p) for p in parsed] == [len(r["strategies"]) for r in rows]
    assert any(s["target_x"] is None for p in parsed for s in p)
    assert parsed[rows.index(full)][0]["pass_cmd_catch_x"] == first["pass_cmd_catch_x"]
    # numbers in lists read back to the recorded float32 values
    seen = pq.read_table(folder / "perception_robots.parquet").column("seen_wheel_speeds").to_pylist()
    as_text = _read(csv_folder, "perception_robots", "csv").column("seen_wheel_speeds").to_pylist()
    assert len(seen) == len(as_text)
    for want, got in list(zip(seen, as_text))[::97]:
        assert np.array(json.loads(got, parse_constant=strict), dtype=np.float32).tolist() == want


def test_the_docs_list_the_tables_export_writes(refereed, tables):
    doc = (ROOT / "docs" / "recording.md").read_text(encoding="utf-8")
    section = doc.split("## Datasets", 1)[1].split("\n## ", 1)[0]
    documented = set()
    for line in section.splitlines():
        if line.startswith("| `"):
            documented |= set(re.findall(r"`([a-z_]+)`", line.split("|")[1]))
    _, counts = tables["parquet"]
    assert set(counts) <= documented, f"written but not documented: {set(counts) - documented}"
    assert documented - set(counts) == {"link_trajectories"}, "documented but not written"
    assert "--record-links" in section  # when link_trajectories is there
