"""``simatch run SCENE --realtime --ros2``: an embedded run watched from ROS 2 by the observer bridge, which
runs in a process of its own; checked from plain rclpy processes (markers, /tf, game commands, and a ball
placed through the privileged set_model_state topic)."""

from __future__ import annotations

import json

import pytest

from .conftest import RosProcesses

pytestmark = pytest.mark.slow

KICKOFF = 6.0  # the referee's STOP before the first kick-off [s]
DURATION = 10.0


@pytest.mark.parametrize("command", ["run", "server"])
def test_an_embedded_run_on_the_ros2_graph(rosprocs: RosProcesses, command):
    """``simatch run --ros2``, and ``simatch server --ros2`` (the same observer, beside the server's teams; here
    with no team to wait for)."""
    ps = rosprocs
    watch = ps.client("watch.py", "60", str(ps.tmp / "watch.json"), "cyan", "magenta")
    place = ps.client("place.py", "3.0", "2.0", str(ps.tmp / "place.json"))
    # the referee holds STOP for 6 s before the kick-off (2 s as shipped): time for the clients to find the
    # bridge's process on a busy machine before the commands they must hear
    late = ["--duration", str(DURATION), "--set", f"judge.stop_time={KICKOFF}"]
    if command == "run":
        run = ps.start("run", "msl_5v5", "--realtime", *late, "--ros2", "--quiet", "--json", name="run")
    else:
        alone = ["--set", "teams.cyan.strategy=none", "--set", "teams.magenta.strategy=none"]
        run = ps.server("msl_5v5", "--realtime", *late, "--ros2", *alone)
    assert ps.wait(run, 180) == 0, ps.stderr(run)
    out = json.loads(ps.stdout(run))
    assert ps.wait(place, 60) == 0, ps.stderr(place)
    ps.wait(watch, 90)
    w = json.loads((ps.tmp / "watch.json").read_text())
    robots = {f"robots/{t}:{i}" for t in ("cyan", "magenta") for i in range(1, 6)}
    assert robots <= {m.rsplit(":", 1)[0] for m in w["markers"]}
    assert {f"map->{t}/robot{i}/base_link" for t in ("cyan", "magenta") for i in range(1, 6)} <= set(w["tf"])
    # STOPROBOT, OUR_KICKOFF at 6 s, STARTROBOT at 7 s (the first may come before this client found the bridge)
    cyan, magenta = ([m for _, m in w["modes"][t]] for t in ("cyan", "magenta"))
    assert cyan[cyan.index(1) :][:2] == [1, 15] and set(cyan[: cyan.index(1)]) <= {0}, cyan
    assert magenta[magenta.index(2) :][:2] == [2, 15] and set(magenta[: magenta.index(2)]) <= {0}, magenta  # mirrored
    assert abs(w["clock"][-1] - DURATION) < 0.1 and out["sim_seconds"] == pytest.approx(DURATION)
    p = json.loads((ps.tmp / "place.json").read_text())
    # the ball left the centre for the spot (the simulator pushes a placed ball out of a robot that stands there:
    # in a run of moving robots, a few centimetres off)
    assert any(abs(x - 3.0) < 0.25 and abs(y - 2.0) < 0.25 for _, x, y in p["after"]), p
    # the bridge left with the run
    assert "the run is over" in ps.stderr(run)


def test_the_observer_does_not_change_the_run(rosprocs: RosProcesses):
    ps = rosprocs
    digests = []
    for extra in ((), ("--ros2",)):
        p = ps.start("run", "msl_5v5", "--duration", "3", "--quiet", "--json", *extra, name="run")
        assert ps.wait(p, 180) == 0, ps.stderr(p)
        digests.append(json.loads(ps.stdout(p))["state_digest"])
    assert digests[0] == digests[1]
