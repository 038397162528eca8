"""A quadrotor (``model = "quadrotor"``): the aerial robot model, a rigid body lifted by four rotors.

The defaults are those of the Bitcraze Crazyflie 2.0, the nano quadrotor most research groups fly, as
identified by J. Förster, *System Identification of the Crazyflie 2.0 Nano Quadrocopter* (ETH Zürich,
2015) and collected in gym-pybullet-drones' ``cf2x.urdf`` (Panerati et al., IROS 2021):

========================  ==============  ========================================================
mass                      0.027 kg        Förster 2015; cf2x.urdf
arm length                0.0397 m        centre to rotor axis (cf2x.urdf ``arm``)
inertia Ixx, Iyy, Izz     1.4e-5, 1.4e-5, 2.17e-5 kg m^2 (cf2x.urdf, from Förster 2015)
propeller radius          0.0231 m        cf2x.urdf ``prop_radius``
thrust-to-weight          2.25            cf2x.urdf ``thrust2weight``: each rotor lifts at most
                                          2.25 * 0.027 kg * g / 4 = 0.149 N
drag torque / thrust      0.0251 m        km / kf = 7.94e-12 / 3.16e-10 (cf2x.urdf)
rotor drag (linear)       0.053 N s/m (x, y), 0.060 N s/m (z): cf2x.urdf ``drag_coeff_xy`` 9.1785e-7
                                          and ``drag_coeff_z`` 10.311e-7 N/(rpm m/s) times the four
                                          rotors' speeds at hover (4 x 14 468 rpm)
motor time constant       0.05 s          first-order thrust lag; Bitcraze measured a Crazyflie 2.0
                                          motor from zero to 25 000 rpm in about 180 ms ("Measuring
                                          propeller RPM, part 3", 2015): 3.6 time constants
========================  ==============  ========================================================

The onboard controller's settings (speed limits, gains) are simatch's own, tuned on this airframe and
measured in docs/aerial.md. Every value can be set per team in the scene (``model_params``).
"""

from __future__ import annotations

import math
from typing import ClassVar

from pydantic import BaseModel, ConfigDict, Field

from .base import RobotModel

#: standard gravity, at which a thrust-to-weight ratio is stated [m/s^2]
STANDARD_GRAVITY = 9.80665


class QuadrotorParams(BaseModel):
    """The airframe (Crazyflie 2.0 by default), its onboard controller and its downward camera."""

    model_config = ConfigDict(extra="forbid")
    # --- airframe ---------------------------------------------------------------------------------------
    mass: float = Field(0.027, gt=0.005, le=50.0, description="[kg]")
    arm_length: float = Field(0.0397, gt=0.01, le=2.0, description="centre to each rotor's axis [m]")
    prop_radius: float = Field(0.0231, gt=0.0, le=1.0, description="[m]")
    frame_height: float = Field(0.03, gt=0.005, le=1.0, description="height of the frame's collision box [m]")
    ixx: float = Field(1.4e-5, gt=0.0, le=100.0, description="roll inertia [kg m^2]")
    iyy: float = Field(1.4e-5, gt=0.0, le=100.0, description="pitch inertia [kg m^2]")
    izz: float = Field(2.17e-5, gt=0.0, le=100.0, description="yaw inertia [kg m^2]")
    thrust_to_weight: float = Field(
        2.25, gt=1.0, le=10.0, description="all four rotors' largest thrust over the weight at standard gravity"
    )
    torque_ratio: float = Field(0.0251, ge=0.0, le=1.0, description="a rotor's drag torque per newton of thrust [m]")
    motor_time_constant: float = Field(0.05, gt=0.0, le=1.0, description="first-order lag of each rotor's thrust [s]")
    drag_xy: float = Field(0.053, ge=0.0, le=100.0, description="linear rotor drag along the body's x and y [N s/m]")
    drag_z: float = Field(0.060, ge=0.0, le=100.0, description="linear rotor drag along the body's z [N s/m]")
    start_altitude: float = Field(
        1.0, ge=0.0, le=100.0, description="height of the body's centre at the start [m]; 0: landed, motors off"
    )
    # --- onboard controller (velocity -> attitude -> rates -> rotor thrusts) ---------------------------------
    max_speed: float = Field(3.0, gt=0.0, le=30.0, description="horizontal speed commands are capped here [m/s]")
    max_climb: float = Field(2.0, gt=0.0, le=30.0, description="upward speed commands are capped here [m/s]")
    max_descent: float = Field(1.5, gt=0.0, le=30.0, description="downward speed commands are capped here [m/s]")
    max_yaw_rate: float = Field(3.0, gt=0.0, le=30.0, description="turn commands are capped here [rad/s]")
    max_tilt: float = Field(35.0, gt=1.0, le=80.0, description="largest tilt the controller asks for [deg]")
    position_gain: float = Field(
        1.5, ge=0.0, le=50.0, description="pull back onto the commanded path (hover hold) [1/s]"
    )
    velocity_gain: float = Field(4.0, gt=0.0, le=100.0, description="velocity loop [1/s]")
    velocity_integral: float = Field(3.0, ge=0.0, le=100.0, description="velocity loop's integral [1/s^2]")
    attitude_gain: float = Field(9.0, gt=0.0, le=500.0, description="attitude loop [1/s]")
    rate_gain: float = Field(25.0, gt=0.0, le=2000.0, description="body-rate loop [1/s]")
    leash: float = Field(
        0.5, gt=0.0, le=20.0, description="the hold point stays this close to the body (after a push) [m]"
    )
    # --- downward camera -----------------------------------------------------------------------------------
    camera_half_angle: float = Field(
        55.0,
        gt=0.0,
        lt=90.0,
        description="half-angle of the downward camera's cone (perception.camera_footprint) [deg]",
    )


class Quadrotor(RobotModel):
    """Four rotors in an X (rotor k at 45 + 90 k degrees from the nose), spinning alternately: rotors 1 and
    3 counter-clockwise seen from above, 2 and 4 clockwise, so that their drag torques cancel in hover."""

    name = "quadrotor"
    Params: ClassVar[type[BaseModel]] = QuadrotorParams
    locomotion = "aerial"
    rotor_angles: ClassVar[tuple[float, ...]] = (math.pi / 4, 3 * math.pi / 4, -3 * math.pi / 4, -math.pi / 4)
    #: +1: the rotor spins counter-clockwise seen from above, so its drag torque turns the body clockwise
    rotor_spin: ClassVar[tuple[int, ...]] = (1, -1, 1, -1)

    @property
    def mass(self) -> float:
        return self.params.mass

    def inertia(self) -> tuple[float, float, float]:
        p = self.params
        return (p.ixx, p.iyy, p.izz)

    @property
    def max_rotor_thrust(self) -> float:
        """The most one rotor lifts [N]."""
        p = self.params
        return p.thrust_to_weight * p.mass * STANDARD_GRAVITY / len(self.rotor_angles)

    def rotor_positions(self) -> list[tuple[float, float]]:
        """(x, y) of each rotor's axis in the body frame (x forward, y left) [m]."""
        a = self.params.arm_length
        return [(a * math.cos(t), a * math.sin(t)) for t in self.rotor_angles]

    @property
    def radius(self) -> float:
        """Footprint radius: the rotor discs' outer edge [m]."""
        return self.params.arm_length + self.params.prop_radius

    @property
    def height(self) -> float:
        return self.params.frame_height

    def collision_half_sizes(self) -> tuple[float, float, float]:
        """The frame's collision box (half sizes): it covers the four rotor discs."""
        p = self.params
        half = p.arm_length * math.sqrt(0.5) + p.prop_radius
        return (half, half, p.frame_height / 2)

    # a quadrotor has neither wheels nor a ball mouth: what the ground-robot interface asks is answered
    # with what keeps a ball clear of it
    def mouth_x(self, ball_radius: float) -> float:
        return self.radius + ball_radius

    def ball_collider(self, ball_radius: float) -> tuple[float, float]:
        return (0.0, self.radius)
