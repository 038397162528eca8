"""scripts/bench_regression.py: the reference figures of docs/performance.md against a bench's output, and
the ratios `simatch bench` adds when it ran both the physics and the match."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from simatch.cli.bench import ratios

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "bench_regression.py"


def _check(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True, timeout=60)


def _reference(figure: str) -> float:
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import bench_regression
    finally:
        sys.path.pop(0)
    return {r["figure"]: r["value"] for r in bench_regression.references()}[figure]


def test_bench_adds_the_match_to_physics_ratios_of_one_run():
    out = ratios({"physics_rtf": 160.0, "match_rtf": 80.0, "physics_cpu_rtf": 170.0, "match_cpu_rtf": 85.0})
    assert out == {"match_physics_ratio": 0.5, "match_physics_cpu_ratio": 0.5}
    assert ratios({"match_rtf": 30.0}) == {} and ratios({"physics_rtf": 0.0, "match_rtf": 3.0}) == {}


def test_figures_as_good_as_the_reference_pass_and_a_slower_match_is_named(tmp_path):
    ref = _reference("match_cpu_rtf")
    same = tmp_path / "same.json"
    same.write_text(json.dumps({"match_cpu_rtf": ref * 0.95}))
    ok = _check("--from", str(same), "--only", "match_cpu_rtf", "--json")
    assert ok.returncode == 0, ok.stderr
    (line,) = json.loads(ok.stdout)["figures"]
    assert line["verdict"] == "ok" and line["change_pct"] == -5.0

    slow = tmp_path / "slow.json"
    slow.write_text("[2/2] running match ...\n" + json.dumps({"match_cpu_rtf": ref * 0.8}))  # the last line counts
    bad = _check("--from", str(slow), "--only", "match_cpu_rtf")
    assert bad.returncode == 1
    assert "match_cpu_rtf" in bad.stdout and "-20.0%" in bad.stdout and "worse" in bad.stdout


def test_lower_is_better_figures_and_missing_ones(tmp_path):
    ref = _reference("match_decide_us_per_robot_tick")
    f = tmp_path / "bench.json"
    f.write_text(json.dumps({"match_decide_us_per_robot_tick": ref / 2}))
    out = _check("--from", str(f), "--json")
    assert out.returncode == 0, out.stderr
    figures = {v["figure"]: v for v in json.loads(out.stdout)["figures"]}
    assert figures["match_decide_us_per_robot_tick"]["change_pct"] == 50.0  # half the time: 50 % better
    assert figures["physics_rtf"]["verdict"] == "missing"


def test_bad_input_is_one_clear_line(tmp_path):
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    out = _check("--from", str(broken))
    assert out.returncode == 2 and "not the JSON of simatch bench --json" in out.stderr
    unknown = _check("--only", "no_such_figure")
    assert unknown.returncode == 2 and "no reference for no_such_figure" in unknown.stderr


def test_match_instructions_refuses_bad_arguments_before_starting_valgrind():
    script = ROOT / "scripts" / "match_instructions.py"
    out = subprocess.run([sys.executable, str(script), "--seconds", "0"], capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "--seconds must be positive" in out.stderr
