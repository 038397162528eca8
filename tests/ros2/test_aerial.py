"""A drone flown from ROS 2: cmd_vel's linear.z is its upward speed, odom carries its height and climb.

aerial_encirclement (its nine ground chasers and three quadrotors, landed with their motors off; magenta
standing) and quadrotor_flight (one drone, its flight-test judge off), each served in real time with cyan
played from ROS 2. A plain rclpy client (tests/ros2/clients/drive.py) flies a drone forward and up through
cyan's team bridge and records its odom.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from .conftest import RosProcesses

pytestmark = pytest.mark.slow

VX, VZ = 0.5, 1.0  # [m/s] forward and upward
#: (scene, the drone flown, the scene's settings): cyan's first quadrotor in aerial_encirclement (after the nine
#: ground robots), and the single drone of quadrotor_flight with its flight-test judge off (ROS flies it)
SCENES = {
    "aerial_encirclement": (10, ["--set", "teams.magenta.strategy=none"]),
    "quadrotor_flight": (1, ["--set", 'judge={kind="none"}']),
}


@pytest.fixture(scope="module", params=list(SCENES))
def flight(request, tmp_path_factory, ros_interfaces):
    tmp = tmp_path_factory.mktemp("ros2aerial")
    drone, settings = SCENES[request.param]
    ps = RosProcesses(tmp)
    try:
        server = ps.server(
            request.param, "--realtime", "--duration", "600", "--set", "control.command_timeout=0.5",
            "--set", "teams.cyan.strategy=external", *settings,
        )  # fmt: skip
        ps.wait_for_line(server, "listening", 60)
        observer, team = ps.observer_and_team()
        drive = ps.client(
            "drive.py", f"/cyan/robot{drone}", str(VX), "0", "0", "3.0", str(tmp / "drive.json"), "--vz", str(VZ)
        )
        assert ps.wait(drive, 150) == 0, ps.stderr(drive)
        result = ps.end(server, team, observer)
        yield {"drive": json.loads((tmp / "drive.json").read_text()), "result": result, "drone": drone}
    finally:
        ps.close()


def test_the_drone_climbs_at_the_commanded_speed(flight):
    rows = sorted(flight["drive"]["odom"])  # [stamp, x, y, yaw, vx, vy, w, frame, child, z, vz]
    assert rows and all(r[8] == f"cyan/robot{flight['drone']}/base_link" for r in rows)
    z = np.array([r[9] for r in rows], dtype=float)
    vz = np.array([r[10] for r in rows], dtype=float)
    assert z[0] < 0.2, "the drone starts landed"
    assert z.max() > 1.0, f"the drone never climbed: heights {z.min():.2f}..{z.max():.2f} m"
    climbing = vz[vz > 0.5 * VZ]
    assert climbing.size and abs(float(np.median(climbing)) - VZ) < 0.25, "odom's linear.z is not the climb rate"
    # its height grows as its climb rate says (odom's z and linear.z agree)
    t = np.array([r[0] for r in rows], dtype=float)
    k = np.flatnonzero(vz > 0.8 * VZ)
    if k.size >= 2:
        rise = (z[k[-1]] - z[k[0]]) / max(t[k[-1]] - t[k[0]], 1e-9)
        assert abs(rise - VZ) < 0.3


def test_it_flies_forward_while_climbing_and_the_run_goes_on(flight):
    rows = sorted(flight["drive"]["odom"])
    x = np.array([r[1] for r in rows], dtype=float)
    assert x[-1] - x[0] > 0.5, "the drone did not fly forward (cyan attacks +x: forward is +x in map)"
    assert flight["result"]["sim_seconds"] > 3.0
