"""The plug-in API: strategies named in a scene as "package.module:Class", refused with clear messages when
they cannot be used; the tutorial's example team plays."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import simatch
from simatch.config.loader import SceneError
from simatch.plugins import PluginError

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def plugin_dir(tmp_path, monkeypatch):
    """A folder on sys.path holding test strategy modules."""
    (tmp_path / "good_strats.py").write_text(
        textwrap.dedent("""
        from pydantic import BaseModel, ConfigDict
        from simatch.strategy import Command, RobotStrategy

        class P(BaseModel):
            model_config = ConfigDict(extra="forbid")
            speed: float = 1.0

        class Forward(RobotStrategy):
            Params = P
            def decide(self, world):
                return Command(vx=self.ctx.params.speed)

        class NotAStrategy:
            pass

        class Raises(RobotStrategy):
            def decide(self, world):
                raise RuntimeError("bug in my strategy")
        """)
    )
    (tmp_path / "broken_strats.py").write_text("import no_such_dependency_xyz\n")
    (tmp_path / "raising_strats.py").write_text("raise ValueError('half-written module')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    return tmp_path


def make(strategy: str, **extra):
    ov = {"teams.cyan.strategy": strategy, "teams.magenta.strategy": "none", "judge.kind": "none"}
    ov.update(extra)
    return simatch.Simulation("msl_5v5", overrides=ov)


@pytest.mark.parametrize(
    "spec,expected",
    [
        ("nosuchpackage.mod:Team", "cannot import module 'nosuchpackage.mod'"),
        ("good_strats:Missing", "has no 'Missing'"),
        ("good_strats:NotAStrategy", "neither a simatch.strategy.RobotStrategy nor a TeamStrategy"),
        ("broken_strats:Team", "No module named 'no_such_dependency_xyz'"),
        ("raising_strats:Team", "fails to import: ValueError: half-written module"),
        ("no_colon_here", "expected one of"),
    ],
)
def test_a_strategy_that_cannot_be_used_is_refused_with_the_reason(plugin_dir, spec, expected):
    with pytest.raises((SceneError, PluginError)) as err:
        make(spec)
    message = str(err.value)
    assert expected in message and "teams.cyan.strategy" in message


def test_strategy_params_are_checked_against_the_strategys_model(plugin_dir):
    with pytest.raises(SceneError) as err:
        make("good_strats:Forward", **{"teams.cyan.strategy_params": {"sped": 2.0}})
    assert "teams.cyan.strategy_params" in str(err.value) and "sped" in str(err.value)
    with pytest.raises(SceneError):
        make("nubot", **{"teams.cyan.strategy_params": {"max_speed": -1.0}})


def test_a_user_strategy_drives_its_robots_and_its_errors_do_not_stop_the_run(plugin_dir):
    sim = make("good_strats:Forward", **{"teams.cyan.strategy_params": {"speed": 1.5}})
    x0 = sim.model_states()["cyan/4"].x
    sim.coaches["cyan"].start_play()
    sim.run(seconds=1.0)
    assert sim.model_states()["cyan/4"].x > x0 + 0.5
    sim.close()
    sim = make("good_strats:Raises")
    sim.run(seconds=0.5)
    errors = [e for e in sim.events if e["type"] == "strategy_error"]
    assert errors and "bug in my strategy" in errors[0]["detail"]
    sim.close()


def test_the_cli_refuses_an_unknown_strategy_in_one_line():
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "simatch",
            "run",
            "msl_5v5",
            "--duration",
            "1",
            "--set",
            "teams.cyan.strategy=nosuch.module:Team",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stderr.startswith("simatch: error:") and "nosuch.module" in proc.stderr
    assert proc.stderr.count("\n") == 1


def test_the_tutorial_example_plays_a_refereed_match():
    env = {"PYTHONPATH": str(ROOT / "examples"), "PATH": "/usr/bin:/bin"}
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "simatch",
            "run",
            str(ROOT / "examples" / "striker_vs_simple.toml"),
            "--duration",
            "20",
            "--json",
            "--quiet",
        ],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert set(out["result"]["score"]) == {"cyan", "magenta"}
    assert not [e for e in out["events"] if e["type"] == "strategy_error"]
