"""Dataset export: tidy Parquet and CSV tables whose values are the recorded ones."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
import pytest

from simatch.record import ExportError, Recording, export

SIMATCH = [sys.executable, "-m", "simatch"]


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_tables_hold_the_recorded_values(recording, tmp_path, fmt):
    path, _ = recording
    out = tmp_path / fmt
    proc = subprocess.run(
        SIMATCH + ["export", str(path), "--format", fmt, "--out", str(out)], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    read = (
        (lambda name: pq.read_table(out / f"{name}.parquet"))
        if fmt == "parquet"
        else (lambda name: pacsv.read_csv(out / f"{name}.csv"))
    )
    traj = read("trajectories").to_pydict()
    assert len(traj["t"]) == 400 * 11  # one row per model per physics step
    rec = Recording(path)
    states = {m.step: m for _, _, m in rec.messages(topics={"model_states"})}
    state = states[321]
    pose = np.asarray(state.pose).reshape(-1, 7)
    twist = np.asarray(state.twist).reshape(-1, 6)
    rows = [i for i, s in enumerate(traj["step"]) if s == 321]
    assert [traj["model"][i] for i in rows] == list(state.name)
    k = list(state.name).index("magenta/3")
    i = rows[k]
    assert (traj["team"][i], traj["robot"][i], traj["t"][i]) == ("magenta", 3, pytest.approx(1.605))
    assert [traj[c][i] for c in ("x", "y", "z", "qw", "qx", "qy", "qz")] == list(pose[k])  # exact, CSV too
    assert [traj[c][i] for c in ("vx", "vy", "vz", "wx", "wy", "wz")] == list(twist[k])
    # (the float32 quaternion is unit to 1e-7 only: two formulas for its yaw agree to that)
    assert math.remainder(traj["yaw"][i] - 2 * math.atan2(pose[k, 6], pose[k, 3]), 2 * math.pi) == pytest.approx(
        0.0, abs=1e-6
    )
    ball = rows[-1]
    assert traj["model"][ball] == "ball" and traj["team"][ball] in (None, "")  # CSV: an empty field
    events = read("events").to_pydict()
    assert "coach_command" in events["type"]
    vel = read("vel_cmd").to_pydict()
    assert set(vel) >= {"t", "team", "robot", "vx", "vy", "w", "stamp", "tick"}
    ops = read("operator_command").to_pydict()
    assert ops["call"][:3] == ["coach", "coach", "set_model_state"]
    seen = read("perception_obstacles").to_pydict()
    assert len(seen["t"]) == 80 * 10 * 9  # every robot sees the 9 others each tick
    strat = read("strategy_info").to_pydict()
    assert "pass_cmd_catch_x" in strat
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["metadata"]["seed"] == "4" and meta["tables"]["trajectories"] == 4400


def test_export_never_overwrites(recording, tmp_path):
    path, _ = recording
    export(path, "csv", tmp_path / "t")
    with pytest.raises(ExportError, match="already holds csv tables"):
        export(path, "csv", tmp_path / "t")
    proc = subprocess.run(
        SIMATCH + ["export", str(path), "--format", "xls"], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2 and "invalid choice" in proc.stderr
