"""State readout: the world's exact states as the rest of simatch reads them.

Poses and twists of every model (robots, then the ball) in the world frame, as arrays (float64, or float32
as the ModelStates message carries them) or as `ModelStateView` objects; links (wheels, rotors); the robots'
planar states and body velocities; and the state's fingerprint and digest, by which a re-simulation is
checked against its recording bit for bit.

`StateReadout` is a part of `simatch.sim.simulator.Simulator` (its methods are the simulator's).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from ..compiled import bind
from .flight import aerial_poses, planar, rotor_links, yaw_of
from .kernels import fill_model_states, mix64, model_fingerprint, model_states32
from .world import BALL_NAME

_zeros, _f32 = np.zeros, np.float32

#: how the StateFingerprint of the exact states is taken (a recording says which in its metadata, `FINGERPRINTS`):
#: ``mix64`` (`simatch.sim.kernels.mix64` of the states' 64-bit words) since recording format 2, ``sha256`` (the
#: first 8 bytes of their SHA-256, little endian) before
FINGERPRINT = "mix64"


def fingerprint(pose: np.ndarray, twist: np.ndarray, kind: str = FINGERPRINT) -> int:
    """The StateFingerprint of the exact poses and twists (float64 arrays, as the simulator makes them): their
    numbers, poses then twists, in C order, taken as ``kind`` (`FINGERPRINT`, or ``sha256`` for a recording of
    format 1). Equal fingerprints mean the same states bit for bit (a chance difference is 1 in 1.8e19)."""
    pose, twist = np.ascontiguousarray(pose, np.float64), np.ascontiguousarray(twist, np.float64)
    if kind == "sha256":
        h = hashlib.sha256(pose)
        h.update(twist)
        return int.from_bytes(h.digest()[:8], "little")
    if kind != FINGERPRINT:
        raise ValueError(f"unknown fingerprint {kind!r} (known: {', '.join(FINGERPRINTS)})")
    return int(mix64(np.concatenate((pose.ravel(), twist.ravel())).view(np.uint64)))


FINGERPRINTS = (FINGERPRINT, "sha256")


@dataclass
class ModelStateView:
    """One model's state in the world frame."""

    name: str
    x: float
    y: float
    z: float
    yaw: float
    qw: float
    qx: float
    qy: float
    qz: float
    vx: float
    vy: float
    vz: float
    wx: float
    wy: float
    wz: float


class StateReadout:
    """The simulator's state-reading methods (see the module)."""

    def _init_readout(self) -> None:
        self._model_states32 = bind(model_states32)
        self._model_fingerprint = bind(model_fingerprint)
        # the exact states whose fingerprint a recording takes every control tick: poses then twists, float64,
        # in one block that `model_fingerprint` fills in place and hashes by its 64-bit words
        m = self.n + 1  # the robots and the ball
        self._state64 = np.zeros(13 * m)
        self._words64 = self._state64.view(np.uint64)
        #: how `state_fingerprint` takes it (`FINGERPRINTS`: a re-simulation of an older recording sets its kind)
        self.fingerprint_kind = FINGERPRINT

    # --- states --------------------------------------------------------------------------------------------
    def robot_positions(self) -> np.ndarray:
        """(N, 3) x, y, yaw of every robot (world frame): a view for ground robots alone (valid until the next
        step, do not modify), a new array where aerial robots fly."""
        if self.aerial is None:
            return self.engine.pose
        return self.robot_array()[:, :3]

    def robot_xy(self, i: int) -> np.ndarray:
        """Robot i's x, y (world frame)."""
        if i < self.ng:
            return self.d.qpos[self.ix.robot_qpos[i, :2]]
        a = self.ix.aerial.qpos[i - self.ng]
        return self.d.qpos[a : a + 2].copy()

    def aerial_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Poses (A, 7) and world twists (A, 6) of the aerial robots (empty without them)."""
        if self.aerial is None:
            return np.zeros((0, 7)), np.zeros((0, 6))
        ix = self.ix.aerial
        return aerial_poses(self.d.qpos, self.d.qvel, ix.qpos, ix.qvel)

    def robot_heights(self, aerial: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """(N, 2): z and vz of every robot's origin, world frame (0 for ground robots)."""
        out = np.zeros((self.n, 2))
        if self.aerial is not None:
            pose, twist = aerial or self.aerial_arrays()
            out[self.ng :, 0] = pose[:, 2]
            out[self.ng :, 1] = twist[:, 2]
        return out

    def ball_position(self) -> np.ndarray:
        """(3,) view of the ball's x, y, z (world frame); valid until the next step, do not modify."""
        b = self.engine.ball_q
        return self.d.qpos[b : b + 3]

    def robot_array(self, aerial: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """(N, 6): x y yaw vx vy w of every robot, world frame (an aerial robot's heading and turn rate about
        the vertical; ``aerial``: its `aerial_arrays`, if at hand)."""
        out = np.empty((self.n, 6))
        ng = self.ng
        out[:ng, :3] = self.engine.pose
        out[:ng, 3:] = self.engine.twist
        if self.aerial is not None:
            out[ng:] = planar(*(aerial or self.aerial_arrays()))
        return out

    def ball_array(self) -> np.ndarray:
        """(6,): x y z vx vy vz of the ball, world frame."""
        q, v = self.d.qpos, self.d.qvel
        b, bv = self.engine.ball_q, self.engine.ball_v
        return np.array((q[b], q[b + 1], q[b + 2], v[bv], v[bv + 1], v[bv + 2]))

    def model_state_arrays(self) -> tuple[list[str], np.ndarray, np.ndarray]:
        """Names, poses (M, 7: x y z qw qx qy qz) and twists (M, 6: v, w), world frame; ball last."""
        e, ng = self.engine, self.ng
        pose, twist = np.zeros((ng + 1, 7)), np.zeros((ng + 1, 6))
        fill_model_states(e.qpos, e.qvel, e.robot_q, e.robot_v, ng, e.ball_q, e.ball_v, pose, twist)
        if self.aerial is not None:
            ap, at = self.aerial_arrays()
            pose = np.concatenate((pose[:ng], ap, pose[ng:]))
            twist = np.concatenate((twist[:ng], at, twist[ng:]))
        return self.model_names, pose, twist

    def model_state_arrays32(self) -> tuple[np.ndarray, np.ndarray]:
        """`model_state_arrays`' poses and twists rounded to float32 and flat (M*7,), (M*6,), as the
        ModelStates message carries them: one compiled call, for every physics step's message (in a world with
        drones, whose poses come from the airframes, the float64 arrays rounded)."""
        if self.aerial is not None:
            _, pose, twist = self.model_state_arrays()
            return pose.astype(np.float32).ravel(), twist.astype(np.float32).ravel()
        e, n = self.engine, self.n
        pose, twist = _zeros(7 * (n + 1), _f32), _zeros(6 * (n + 1), _f32)
        self._model_states32(e.qpos, e.qvel, e.robot_q, e.robot_v, n, e.ball_q, e.ball_v, pose, twist)
        return pose, twist

    def state_fingerprint(self) -> int:
        """`fingerprint` of `model_state_arrays`' poses and twists, without making them (a recording takes it at
        every control tick)."""
        if self.aerial is not None or self.fingerprint_kind != FINGERPRINT:
            _, pose, twist = self.model_state_arrays()
            return fingerprint(pose, twist, self.fingerprint_kind)
        e = self.engine
        return self._model_fingerprint(
            e.qpos, e.qvel, e.robot_q, e.robot_v, self.n, e.ball_q, e.ball_v, self._state64, self._words64
        )

    def model_states(self) -> dict[str, ModelStateView]:
        names, pose, twist = self.model_state_arrays()
        out = {}
        for name, p, t in zip(names, pose.tolist(), twist.tolist()):  # plain floats, as a judge reads them
            out[name] = ModelStateView(name, *p[:3], yaw_of(*p[3:]), *p[3:], *t)
        return out

    def link_state_arrays(self) -> tuple[list[str], np.ndarray, np.ndarray]:
        """Every link: each robot's base and wheels (an aerial robot's base and rotors), and the ball. Same
        layout as model states.

        A wheel's pose is its hub centre, with its axle along the line from the robot centre; its
        angular velocity adds the wheel's spin (from its rim speed) to the robot's turn. A rotor's pose is
        its hub, turned with the body; its velocity is the body's at that point."""
        self.track_wheels = True
        names, pose, twist = self.model_state_arrays()
        travel = self.wheel_travel
        U = self.wheel_speeds()
        out_names, out_pose, out_twist = [], [], []
        for i, rname in enumerate(self.robot_names):
            rm = self.robot_models[i]
            out_names.append(f"{rname}/base")
            out_pose.append(pose[i])
            out_twist.append(twist[i])
            if i >= self.ng:
                for k, (p, v) in enumerate(rotor_links(rm, pose[i], twist[i])):
                    out_names.append(f"{rname}/rotor_{k + 1}")
                    out_pose.append(p)
                    out_twist.append(v)
                continue
            x, y, _, qw, _, _, qz = pose[i]
            yaw = 2.0 * math.atan2(qz, qw)
            r = rm.params.wheel_radius
            for k, wheel in enumerate(rm.wheels):
                a = yaw + wheel.alpha
                cx, cy = x + wheel.distance * math.cos(a), y + wheel.distance * math.sin(a)
                spin = travel[i, k] / r
                # orientation: yaw to the wheel's radial direction, then spin about that (local x) axis
                qa = (math.cos(a / 2), 0.0, 0.0, math.sin(a / 2))
                qs = (math.cos(spin / 2), math.sin(spin / 2), 0.0, 0.0)
                quat = np.empty(4)
                mujoco.mju_mulQuat(quat, np.array(qa), np.array(qs))
                wz = twist[i, 5]
                spin_rate = U[i, k] / r
                vx = twist[i, 0] - wz * (cy - y)
                vy = twist[i, 1] + wz * (cx - x)
                out_names.append(f"{rname}/wheel_{k + 1}")
                out_pose.append(np.array((cx, cy, r, *quat)))
                out_twist.append(np.array((vx, vy, 0.0, spin_rate * math.cos(a), spin_rate * math.sin(a), wz)))
        out_names.append(BALL_NAME)
        out_pose.append(pose[self.n])
        out_twist.append(twist[self.n])
        return out_names, np.array(out_pose), np.array(out_twist)

    def digest(self) -> str:
        """Hex SHA-256 of every model's state: equal digests mean the same run, bit for bit."""
        names, pose, twist = self.model_state_arrays()
        h = hashlib.sha256()
        h.update("\n".join(names).encode())
        h.update(np.ascontiguousarray(pose).tobytes())
        h.update(np.ascontiguousarray(twist).tobytes())
        return h.hexdigest()

    # --- the Gazebo-like interface ------------------------------------------------------------------------------
