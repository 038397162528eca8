"""Building an aerial robot into the MuJoCo world (MjSpec), and where its parts lie in the compiled model.

A quadrotor is a free rigid body (six degrees of freedom) with its mass and inertia, a collision box that
covers its rotor discs, and seven actuators the engine computes on its own, with no Python:

* four rotors, one per arm: a site actuator at the rotor's axis whose force pushes along the body's z and
  whose torque about z is the rotor's drag torque (gear [0, 0, 1, 0, 0, -spin * torque_ratio]). Its
  control is the commanded thrust, limited to [0, the rotor's largest thrust]; its activation, the thrust
  it gives, follows the command with the motor's first-order lag (exact filter dynamics);
* three rotor-drag dampers along the body's x, y and z: a force of -drag times the body's velocity along
  that axis (affine bias actuators), which is what caps a climb at full thrust.

Gravity acts on it like on everything else; contacts with the floor, walls, obstacles, robots, the ball
and other drones are the engine's (a drone that hits something bounces off or falls; it is never moved
by hand). Its onboard controller sets the rotors' commands every physics step (`simatch.sim.flight`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from ..robots.body import add_freeze_weld

#: contact of a drone's frame: stiff, and less than critically damped so that a drone that hits a wall
#: comes off it (returns about a fifth of the impact speed) rather than sticking
AIRFRAME_SOLREF = [0.01, 0.5]


@dataclass
class AerialIndex:
    """Addresses of the aerial robots (one row each, in robot order after the ground robots)."""

    robots: np.ndarray  # (A,) robot indices (the simulator's)
    body: np.ndarray  # (A,) body ids
    qpos: np.ndarray  # (A,) address of each free joint's 7 numbers: x y z qw qx qy qz
    qvel: np.ndarray  # (A,) address of its 6 numbers: vx vy vz (world) wx wy wz (body frame)
    rotor: np.ndarray  # (A, 4) actuator ids of the rotors
    rotor_act: np.ndarray  # (A, 4) their activation addresses (the thrust each gives now)
    geom: np.ndarray  # (A,) the frame's collision geom
    freeze_eq: np.ndarray  # (A,) weld to the world (inactive)


def add_airframe(spec: mujoco.MjSpec, entry, contype: int, conaffinity: int) -> None:
    """Add ``entry`` (a RobotEntry whose model is aerial) to ``spec``, at its start pose and altitude."""
    model = entry.model
    p = model.params
    x, y, yaw = entry.start
    z = max(p.start_altitude, model.collision_half_sizes()[2])
    body = spec.worldbody.add_body(
        name=entry.name, pos=[x, y, z], quat=[math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
    )
    body.add_freejoint(name=f"{entry.name}/free")
    body.mass = model.mass
    body.inertia = list(model.inertia())
    body.ipos = [0.0, 0.0, 0.0]
    body.explicitinertial = True
    body.add_geom(
        name=f"{entry.name}/hull",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(model.collision_half_sizes()),
        contype=contype,
        conaffinity=conaffinity,
        condim=3,
        friction=[0.5, 0.005, 0.0001],
        solref=AIRFRAME_SOLREF,
        mass=0,
    )
    body.add_site(name=f"{entry.name}/base", pos=[0, 0, 0])
    fmax = model.max_rotor_thrust
    for k, ((rx, ry), spin) in enumerate(zip(model.rotor_positions(), model.rotor_spin)):
        site = f"{entry.name}/rotor_{k + 1}"
        body.add_site(name=site, pos=[rx, ry, 0.0])
        act = spec.add_actuator(
            name=site,
            trntype=mujoco.mjtTrn.mjTRN_SITE,
            target=site,
            gear=[0, 0, 1, 0, 0, -spin * p.torque_ratio],
        )
        act.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
        act.dynprm[0] = p.motor_time_constant
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.gainprm[0] = 1.0
        act.biastype = mujoco.mjtBias.mjBIAS_NONE
        act.ctrllimited = True
        act.ctrlrange = [0.0, fmax]
    for axis, drag in ((0, p.drag_xy), (1, p.drag_xy), (2, p.drag_z)):
        gear = [0.0] * 6
        gear[axis] = 1.0
        act = spec.add_actuator(
            name=f"{entry.name}/drag_{'xyz'[axis]}",
            trntype=mujoco.mjtTrn.mjTRN_SITE,
            target=f"{entry.name}/base",
            gear=gear,
        )
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.gainprm[0] = 0.0
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.biasprm[0:3] = [0.0, 0.0, -drag]
    add_freeze_weld(spec, entry.name, [0.02, 1.0])


def aerial_index(model: mujoco.MjModel, data: mujoco.MjData, entries, first: int, gravity: float) -> AerialIndex:
    """The compiled addresses of the aerial robots ``entries`` (robot indices from ``first`` on); a drone
    that starts in the air starts in hover, each rotor already giving a quarter of its weight."""

    def rotors(name):
        return [model.actuator(f"{name}/rotor_{k + 1}").id for k in range(4)]

    ix = AerialIndex(
        robots=np.arange(first, first + len(entries)),
        body=np.array([model.body(e.name).id for e in entries], dtype=int),
        qpos=np.array([model.jnt_qposadr[model.joint(f"{e.name}/free").id] for e in entries], dtype=int),
        qvel=np.array([model.jnt_dofadr[model.joint(f"{e.name}/free").id] for e in entries], dtype=int),
        rotor=np.array([rotors(e.name) for e in entries], dtype=int).reshape(-1, 4),
        rotor_act=np.array([[model.actuator_actadr[a] for a in rotors(e.name)] for e in entries], dtype=int).reshape(
            -1, 4
        ),
        geom=np.array([model.geom(f"{e.name}/hull").id for e in entries], dtype=int),
        freeze_eq=np.array([model.equality(f"{e.name}/freeze").id for e in entries], dtype=int),
    )
    for k, e in enumerate(entries):
        if e.model.params.start_altitude > 0.0:
            hover = e.model.mass * gravity / 4
            data.act[ix.rotor_act[k]] = hover
            data.ctrl[ix.rotor[k]] = hover
    return ix
