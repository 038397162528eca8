"""The chaos test (scripts/chaos.py) of a lockstep and a real-time match: processes killed, stopped, restarted,
their Zenoh traffic held up, delayed and cut, and afterwards the server never stopped, every fault is in the
event log, the recording is complete and it re-simulates bit for bit from its recorded inputs. The assertions
are about correctness only: on a loaded two-core machine the real-time run may fall behind."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from simatch.record import Recording, verify

from .cluster import CHASER, ROOT


@pytest.mark.slow
@pytest.mark.parametrize(
    "mode, duration, kinds",
    # lockstep runs ahead while a restarted process warms up (it is not waited for): a longer match, and the
    # quick faults first, so that several fit in on a loaded machine too
    [("lockstep", 120, "stop,stall,kill,cut,restart"), ("realtime", 24, "kill,delay,restart,stop,cut")],
)
def test_a_match_under_faults_is_recorded_whole_and_reproduced(tmp_path, mode, duration, kinds):
    cmd = [sys.executable, str(ROOT / "scripts" / "chaos.py"), "--mode", mode, "--duration", str(duration)]
    cmd += ["--faults", "5", "--kinds", kinds, "--cycle", "--fault-seed", "7", "--gap", "0.5", "--until", "0.8"]
    cmd += ["--set", f"teams.cyan.strategy={CHASER}", "--set", f"teams.magenta.strategy={CHASER}"]
    cmd += ["--out", str(tmp_path), "--json", "--timeout", "400"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, cwd=ROOT)
    report = json.loads(proc.stdout)
    (run,) = report["runs"]
    assert report["ok"] and proc.returncode == 0, json.dumps(run, indent=1)[-4000:]
    assert len(run["faults"]) >= 2  # as many as the run had time for (a loaded machine decides how many)
    assert all(f["logged"] for f in run["faults"])
    # the same checks, made here again on the files the script left
    rec = Recording(run["recording"])
    assert rec.finalised and not rec.problems and rec.end["status"] == "complete"
    assert rec.duration == pytest.approx(duration - 0.005)
    events = {m.type for _, _, m in rec.messages(topics={"events"})}
    assert {"process_joined", "watchdog_stop"} <= events
    verdict = verify(run["recording"])
    assert verdict.identical and verdict.complete and verdict.mode == "inputs", verdict.describe()
