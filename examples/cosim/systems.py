"""The paper's two composed systems, and the linear closed loop they are checked against.

- plant + controller: Controller.M1/M2 drive Pendulum.M1/M2 (the paper's Figure 7 setting);
- plant + two DC motors + controller: Controller.U1/U2 -> DCMotor.U, Pendulum.omega_i ->
  DCMotor.omega, DCMotor.tau -> Pendulum.M_i (Figure 8). The paper's motors cannot hold the
  pendulum (stall torque 0.012 N.m at 6 V); the demo motor has a 200:1 gearbox and a realistic
  friction (docs/composition.md).

The same two systems are written as SSP files by `fmu-build ssp`; tests check they agree.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from .master import Component, Connection, System

ALPHA1_0 = 0.1
ALPHA2_0 = -0.05

#: The demo's motor: the paper's electrical constants with a 200:1 gearbox and friction typical
#: of a small DC motor. The controller computes its voltages for the same motor.
DEMO_MOTOR = {"gear_ratio": 200.0, "B": 1e-6}

STATE = ("alpha1", "omega1", "alpha2", "omega2")


def plant_and_controller(pendulum_fmu: str, controller_fmu: str, alpha1=ALPHA1_0, alpha2=ALPHA2_0, mode=1) -> System:
    return System(
        "PendulumLQR",
        (
            Component("pendulum", pendulum_fmu, {"alpha1": alpha1, "alpha2": alpha2}),
            Component("controller", controller_fmu, {"mode": mode}),
        ),
        tuple(Connection("pendulum", s, "controller", s) for s in STATE)
        + (
            Connection("controller", "M1", "pendulum", "M1"),
            Connection("controller", "M2", "pendulum", "M2"),
        ),
    )


def plant_motors_controller(
    pendulum_fmu: str, controller_fmu: str, motor_fmu: str, alpha1=ALPHA1_0, alpha2=ALPHA2_0, mode=3
) -> System:
    motor_start = dict(DEMO_MOTOR)
    controller_start = {
        "mode": mode,
        "gear_ratio": DEMO_MOTOR["gear_ratio"],
        "motor_B": DEMO_MOTOR["B"],
        "drives_motors": True,
    }
    return System(
        "PendulumMotors",
        (
            Component("pendulum", pendulum_fmu, {"alpha1": alpha1, "alpha2": alpha2}),
            Component("controller", controller_fmu, controller_start),
            Component("motor1", motor_fmu, motor_start),
            Component("motor2", motor_fmu, motor_start),
        ),
        tuple(Connection("pendulum", s, "controller", s) for s in STATE)
        + (
            Connection("controller", "U1", "motor1", "U"),
            Connection("controller", "U2", "motor2", "U"),
            Connection("pendulum", "omega1", "motor1", "omega"),
            Connection("pendulum", "omega2", "motor2", "omega"),
            Connection("motor1", "tau", "pendulum", "M1"),
            Connection("motor2", "tau", "pendulum", "M2"),
        ),
    )


def closed_loop_matrices(k: np.ndarray, m1=0.5, m2=0.5, l1=1.0, l2=1.0, g=9.81):
    """A and B of the paper's linearization (12), from its mass matrix and gravity terms, and
    A - B K. Written independently of the Rust model (the tests compare the two)."""
    mass = np.array([[(m1 + m2) * l1**2 / 3, m2 * l1 * l2 / 3], [m2 * l1 * l2 / 3, m2 * l2**2 / 3]])
    stiffness = np.diag([m1 * g * l1 / 2 + m2 * g * l1, m2 * g * l2 / 2])
    minv = np.linalg.inv(mass)
    a = np.zeros((4, 4))
    b = np.zeros((4, 2))
    a[0, 1] = a[2, 3] = 1.0
    acc = minv @ stiffness
    a[1, 0], a[1, 2], a[3, 0], a[3, 2] = acc[0, 0], acc[0, 1], acc[1, 0], acc[1, 1]
    b[1], b[3] = minv[0], minv[1]
    return a, b, a - b @ k


def linear_response(acl: np.ndarray, x0, times) -> np.ndarray:
    """x(t) = exp(Acl t) x0 at the given times, shape (len(times), 4)."""
    return np.array([scipy.linalg.expm(acl * t) @ np.asarray(x0, float) for t in times])
