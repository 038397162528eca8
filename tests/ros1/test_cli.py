"""Mistakes get one clear line and exit 2: a team that is not in the scene, no ROS master, no team."""

from __future__ import annotations

import subprocess

import pytest

from tests.ros1.conftest import ROOT, SIMATCH, free_port

pytestmark = pytest.mark.slow


def simatch(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*SIMATCH, *args], cwd=ROOT, capture_output=True, text=True, timeout=120)


def one_line_error(out: subprocess.CompletedProcess, *words: str) -> None:
    """Exit 2 and one error line (a server says where it listened first)."""
    assert out.returncode == 2, out
    lines = [line for line in out.stderr.strip().splitlines() if not line.startswith("simatch server:")]
    assert len(lines) == 1 and lines[0].startswith("simatch: error:"), out.stderr
    for w in words:
        assert w in lines[0], lines[0]


def test_mistakes_are_one_line(tmp_path):
    one_line_error(simatch("run", "msl_5v5", "--ros1", "blue", "--duration", "1"), "no team blue")
    nobody = f"http://127.0.0.1:{free_port()}"
    one_line_error(
        simatch("run", "msl_5v5", "--ros1", "cyan", "--duration", "1", "--ros-master", nobody),
        "no ROS master answers",
        nobody,
    )
    one_line_error(simatch("ros1"), "give the TEAM")
    server = ["server", "msl_5v5", "--listen", f"tcp/127.0.0.1:{free_port()}", "--credentials", str(tmp_path / "c")]
    one_line_error(simatch(*server, "--ros1", "cyan", "--duration", "1"), "simatch ros1 TEAM --connect")
    out = simatch("ros1", "--print-env")
    assert out.returncode == 0 and "ROS_PACKAGE_PATH=" in out.stdout and "PYTHONPATH=" in out.stdout
