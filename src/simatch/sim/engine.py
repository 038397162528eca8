"""Named views of the MuJoCo engine's arrays: what the simulator's kernels read and write.

The engine keeps its state in flat arrays (``qpos``, ``qvel``, ``act``, ...) whose memory is fixed for the
model's and the data's life. The simulator reads and writes parts of them every physics step and every
control tick: the ground robots' planar joints, their base servos, the ball's free joint. This module takes
those parts once, as views with names (no copy, no lookup while stepping), and checks the layout they rely
on — the ground robots' joints and servos consecutive, in robot order — with errors that say what is wrong
(a world built otherwise would have the kernels read another robot's numbers).
"""

from __future__ import annotations

import mujoco
import numpy as np


class WorldLayoutError(RuntimeError):
    """The world's arrays are not laid out as the simulator reads them (a bug of the world's building)."""


def _require(condition: bool, what: str) -> None:
    if not condition:
        raise WorldLayoutError(what)


class EngineViews:
    """The engine's arrays as the simulator uses them, for the ``ng`` ground robots and the ball.

    Ground robot ``i``'s planar joints are ``pose[i]`` (x, y, yaw; world frame) and ``twist[i]`` (vx, vy, w);
    its base servo (one per body axis: x, y, turn) has its set point ``setpoint[i]`` (the actuators'
    activations), the set point's rate ``rate[i]`` (their ctrl), bounds ``setpoint_range[i]`` (actrange),
    gains ``gain[i]`` and bias parameters ``biasprm[i]`` (the model's). The ball's free joint starts at
    ``qpos[ball_q]`` (x y z qw qx qy qz) and ``qvel[ball_v]`` (vx vy vz wx wy wz, the spin in the ball's own
    frame)."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, index, ng: int):
        self.qpos, self.qvel = data.qpos, data.qvel
        #: the same memory as memoryviews, whose items are plain floats (for single numbers)
        self.qpos_flat, self.qvel_flat = memoryview(self.qpos), memoryview(self.qvel)
        self.geom_xpos = data.geom_xpos
        rq, rv = index.robot_qpos, index.robot_qvel
        self.robot_q, self.robot_v = (int(rq[0, 0]), int(rv[0, 0])) if ng else (0, 0)
        q0, v0 = self.robot_q, self.robot_v
        _require(
            np.array_equal(rq.ravel(), np.arange(q0, q0 + 3 * ng))
            and np.array_equal(rv.ravel(), np.arange(v0, v0 + 3 * ng)),
            "the ground robots' joints (x, y, yaw) are not consecutive in robot order",
        )
        servos = np.arange(3 * ng)
        _require(
            np.array_equal(index.robot_ctrl.ravel(), servos) and np.array_equal(index.robot_act.ravel(), servos),
            "the ground robots' base servos are not the model's first actuators in robot order",
        )
        self.pose = self.qpos[q0 : q0 + 3 * ng].reshape(ng, 3)
        self.twist = self.qvel[v0 : v0 + 3 * ng].reshape(ng, 3)
        self.setpoint = data.act[: 3 * ng].reshape(ng, 3)
        self.rate = data.ctrl[: 3 * ng].reshape(ng, 3)
        self.setpoint_range = model.actuator_actrange[: 3 * ng].reshape(ng, 3, 2)
        self.biasprm = model.actuator_biasprm[: 3 * ng].reshape(ng, 3, model.actuator_biasprm.shape[1])
        self.gain = np.ascontiguousarray(model.actuator_gainprm[: 3 * ng, 0].reshape(ng, 3))
        _require(
            ng == 0 or np.shares_memory(self.biasprm, model.actuator_biasprm),
            "the servos' bias parameters are a copy, not the model's (the engine would not see the plans)",
        )
        self.ball_q, self.ball_v = int(index.ball_qpos), int(index.ball_qvel)
        self.ball_z, self.ball_vz = self.ball_q + 2, self.ball_v + 2
