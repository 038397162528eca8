"""A team process whose strategy's kernels were never compiled on this machine compiles them before it
joins (a rehearsal of the scene, then the strategy's ``warm_up``), and the server waits for a connected
process that is still setting up beyond its team timeout: the first lockstep tick finds the team ready, no
tick is missed, and the run equals the embedded one. Once compiled, a process joins at once."""

from __future__ import annotations

import json
import subprocess
import textwrap

import pytest

from .cluster import SIMATCH

PLUGIN = textwrap.dedent(
    '''
    """A Chaser whose decisions call a numba kernel cached next to this file, with a slow set-up hook."""
    import math
    import os
    import time
    from pathlib import Path

    import numba

    from tests.distributed.strategies import Chaser


    @numba.njit(cache=True)
    def heading(x, y):
        return math.atan2(y, x)


    class CompiledChaser(Chaser):
        @classmethod
        def warm_up(cls):
            Path(os.environ["WARM_MARK"]).write_text("warmed")
            time.sleep(6.0)  # a set-up longer than the server's team timeout

        def decide(self, world):
            command = super().decide(world)
            heading(float(self.ctx.id), 1.0)
            return command
    '''
)

OVERRIDES = [
    "--set",
    "teams.cyan.strategy=warmplug:CompiledChaser",
    "--set",
    "teams.cyan.ids=[2]",
    "--set",
    "teams.cyan.start=[[-2.0, 1.0, 0.0]]",
    "--set",
    "teams.magenta.strategy=none",
]


def _lockstep(procs) -> tuple[dict, str, str]:
    # the team process first: it waits for the server (its scene and credential), so that its liveliness token
    # is up within the server's 2 s team timeout however slowly a process starts here; its set-up (the
    # rehearsal and the 6 s warm_up) lasts well beyond the timeout and the server's note 5 s after it began
    team = procs.team("cyan")
    server = procs.server("msl_5v5", "--duration", "2", "--seed", "3", "--team-timeout", "2", *OVERRIDES)
    result = procs.result(server)
    assert procs.wait(team) == 0, procs.stderr(team)
    return result, procs.stderr(server), procs.stderr(team)


@pytest.mark.slow
def test_a_process_compiles_its_kernels_before_joining_and_is_waited_for(procs, tmp_path):
    plug = tmp_path / "plug"
    plug.mkdir()
    (plug / "warmplug.py").write_text(PLUGIN)
    mark = tmp_path / "warmed"
    procs.env["PYTHONPATH"] = f"{plug}:{procs.env['PYTHONPATH']}"
    procs.env["WARM_MARK"] = str(mark)

    result, server_err, team_err = _lockstep(procs)
    assert "compiling its strategy's kernels before joining" in team_err
    assert mark.read_text() == "warmed"  # the strategy's own warm_up ran
    assert list((plug / "__pycache__").glob("warmplug.heading*.nbi")), "the kernel was not compiled and cached"
    assert "setting up" in server_err  # waited for beyond the 2 s team timeout...
    assert not [e for e in result["events"] if e["type"] == "team_absent"]  # ...and not played without
    assert "missed 0" in server_err and "answers 0" not in server_err

    embedded = subprocess.run(
        [*SIMATCH, "run", "msl_5v5", "--duration", "2", "--seed", "3", "--json", "--quiet", *OVERRIDES],
        capture_output=True,
        text=True,
        env=procs.env,
        timeout=300,
    )
    assert embedded.returncode == 0, embedded.stderr
    assert result["state_digest"] == json.loads(embedded.stdout)["state_digest"]

    # compiled now: the next process loads the kernel from the cache and joins without a rehearsal
    mark.unlink()
    again, _, team_err = _lockstep(procs)
    assert "compiling" not in team_err and not mark.exists()
    assert again["state_digest"] == result["state_digest"]
