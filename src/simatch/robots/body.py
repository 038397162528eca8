"""A ground robot's body in the MuJoCo world (MjSpec): its planar joints, collision shapes and base servo.

The robot moves in the plane (slide joints along x and y, a hinge about z) with the mass and inertia of its
model. It collides through two shapes (see `simatch.robots.base`): a hull sphere for robots, goals and
boards, and a mouth capsule for the ball. Its base is driven by a velocity servo per body axis (x, y, turn)
acting in the robot frame through a site at its origin: force = kv (set point - velocity) + bias, bounded
by the traction limit. With the default response time of one physics step it is deadbeat: the base moves
at its set point unless traction limits it. The set point is the actuator's activation, integrated by the
engine from ctrl (its rate of change) and clamped at the target (actrange), so a planned wheel ramp runs
without Python (`simatch.robots.drive.plan_drive` plans it; its bias carries a correction for exact arcs).

The world decides which shapes touch which (the contact groups are the caller's: ``hull`` and ``mouth``
give each shape's contype and conaffinity).
"""

from __future__ import annotations

import mujoco

from .base import HULL_HEIGHT, RobotModel

_AXES = ([1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1])  # the servos' gears: x, y, turn


def add_ground_robot(
    spec: mujoco.MjSpec,
    name: str,
    model: RobotModel,
    *,
    ball_radius: float,
    timestep: float,
    hull: tuple[int, int],
    mouth: tuple[int, int],
    mouth_solref: list[float],
) -> None:
    """Add robot ``name`` of ``model`` to ``spec`` at the world's origin (its joints place it)."""
    p = model.params
    body = spec.worldbody.add_body(name=name, pos=[0.0, 0.0, 0.0])
    body.add_joint(name=f"{name}/x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    body.add_joint(name=f"{name}/y", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
    body.add_joint(name=f"{name}/yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    body.mass = model.mass
    body.inertia = list(model.inertia())
    body.ipos = [0.0, 0.0, p.height / 2]
    body.explicitinertial = True
    body.add_geom(
        name=f"{name}/hull",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        pos=[0, 0, HULL_HEIGHT],
        size=[p.radius, 0, 0],
        contype=hull[0],
        conaffinity=hull[1],
        condim=1,
        mass=0,
    )
    cx, cr = model.ball_collider(ball_radius)
    body.add_geom(
        name=f"{name}/mouth",
        type=mujoco.mjtGeom.mjGEOM_CAPSULE,
        fromto=[cx, 0, ball_radius, cx, 0, max(p.height - cr, ball_radius + 1e-3)],
        size=[cr, 0, 0],
        contype=mouth[0],
        conaffinity=mouth[1],
        condim=3,
        friction=[0.3, 0.005, 0.0001],
        mass=0,
        solref=mouth_solref,
    )
    body.add_site(name=f"{name}/base", pos=[0, 0, 0])
    _add_base_servo(spec, name, model, timestep)


def add_freeze_weld(spec: mujoco.MjSpec, name: str, solref: list[float]) -> None:
    """A weld of body ``name`` to the world, off until the simulator freezes the body where it is."""
    spec.add_equality(
        name=f"{name}/freeze",
        type=mujoco.mjtEq.mjEQ_WELD,
        objtype=mujoco.mjtObj.mjOBJ_BODY,
        name1=name,
        name2="world",
        active=False,
        solref=solref,
    )


def _add_base_servo(spec: mujoco.MjSpec, name: str, model: RobotModel, timestep: float) -> None:
    """The base's velocity servo, one actuator per body axis (see the module)."""
    p = model.params
    tau = p.response_time or timestep
    for k, gear in enumerate(_AXES):
        act = spec.add_actuator(
            name=f"{name}/servo_{'xyw'[k]}", trntype=mujoco.mjtTrn.mjTRN_SITE, target=f"{name}/base", gear=gear
        )
        inertia = model.mass if k < 2 else model.inertia()[2]
        kv = inertia / tau
        act.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.gainprm[0] = kv
        act.biasprm[0:3] = [0.0, 0.0, -kv]
        act.actearly = True
        act.actlimited = True
        act.actrange = [-1.0, 1.0]  # set at run time by every plan
        act.forcelimited = True
        limit = p.max_force if k < 2 else p.max_torque
        act.forcerange = [-limit, limit]
