"""The aerial scenes in lockstep over real Zenoh between real processes equal their embedded runs bit for
bit: drones' commands (with their vertical speed) and perception (with heights, sight rules) cross the
wire unchanged."""

from __future__ import annotations

import json
import subprocess

import pytest

from tests.distributed.cluster import ROOT, SIMATCH


def embedded(procs, scene: str, settings: list[str]) -> dict:
    out = subprocess.run(
        [*SIMATCH, "run", scene, *settings, "--json", "--quiet"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=procs.env,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


@pytest.mark.slow
def test_the_aerial_encirclement_with_a_process_per_team_equals_embedded(procs):
    settings = ["--seed", "2", "--duration", "3"]
    server = procs.server("aerial_encirclement", *settings, "--deadline", "120")
    teams = [procs.team("cyan"), procs.team("magenta")]
    dist = procs.result(server)
    for t in teams:
        assert procs.wait(t) == 0, procs.stderr(t)
    emb = embedded(procs, "aerial_encirclement", settings)
    assert dist["state_digest"] == emb["state_digest"]
    assert dist["sim_seconds"] == emb["sim_seconds"] == 3.0


@pytest.mark.slow
def test_the_3d_pursuit_with_a_process_per_drone_equals_embedded(procs):
    settings = ["--seed", "1", "--duration", "3"]
    server = procs.server("pursuit_evasion_3d", *settings, "--deadline", "120")
    robots = [procs.robot(f"cyan/{rid}") for rid in (1, 2, 3)] + [procs.robot("magenta/1")]
    dist = procs.result(server)
    for r in robots:
        assert procs.wait(r) == 0, procs.stderr(r)
    emb = embedded(procs, "pursuit_evasion_3d", settings)
    assert dist["state_digest"] == emb["state_digest"]
    assert [e for e in dist["events"] if e["type"] == "collision"] == [
        e for e in emb["events"] if e["type"] == "collision"
    ]
