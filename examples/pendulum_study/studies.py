"""The studies: lists of run specs.

- Region of attraction: a grid of initial angles (alpha1, alpha2), for each control law.
- Robustness: Monte Carlo samples of the plant and motor parameters within +-spread of nominal.
  Only the Pendulum and DCMotor FMUs get the sampled values: the Controller keeps its nominal
  plant model (its LQR gain is designed for it) and its nominal motor model (its voltages).
"""

from __future__ import annotations

import numpy as np
from fmpy import read_model_description

from .closed_loop import Criteria, study_systems, system_start
from .runner import make_spec

MODES = {1: "LQR", 2: "PID", 3: "LQR+PID"}

#: Uncertain parameters of the robustness study: plant masses and lengths, and the motors'
#: electrical constants (each motor drawn on its own).
PLANT_UNCERTAIN = ("m1", "m2", "l1", "l2")
MOTOR_UNCERTAIN = ("R", "L", "km", "kb")


def fmu_paths(fmu_dir: str) -> dict[str, str]:
    return {ident: f"{fmu_dir}/{ident}.fmu" for ident in ("Pendulum", "Controller", "DCMotor")}


def nominal(paths: dict[str, str], system: str) -> dict[str, float]:
    """Nominal values of the uncertain parameters: the FMUs' start values, overridden by the
    system's own settings (the SSD's parameter values)."""
    starts = {}
    for ident, path in paths.items():
        starts[ident] = {v.name: float(v.start) for v in read_model_description(path).modelVariables if v.start is not None and v.type == "Real"}
    values = {f"pendulum.{p}": starts["Pendulum"][p] for p in PLANT_UNCERTAIN}
    if system == "motors":
        for m in ("motor1", "motor2"):
            values.update({f"{m}.{p}": starts["DCMotor"][p] for p in MOTOR_UNCERTAIN})
    for k, v in system_start(study_systems(paths)[system]).items():
        if k in values:
            values[k] = float(v)
    return values


def region_of_attraction(
    modes=(1, 2), n=21, amax=0.6, system="torque", stop_time=5.0, step=0.01, criteria=Criteria()
) -> list[dict]:
    """n x n initial angles alpha1, alpha2 in [-amax, amax] rad (at rest), for each mode."""
    grid = np.linspace(-amax, amax, n)
    return [
        make_spec(
            system,
            {"controller.mode": int(mode), "pendulum.alpha1_0": float(a1), "pendulum.alpha2_0": float(a2)},
            stop_time,
            step,
            criteria,
        )
        for mode in modes
        for a1 in grid
        for a2 in grid
    ]


def robustness(
    paths: dict[str, str],
    samples=200,
    spread=0.2,
    seed=1,
    modes=(1, 3),
    system="motors",
    alpha0=(0.1, -0.05),
    stop_time=5.0,
    step=0.01,
    criteria=Criteria(),
) -> list[dict]:
    """`samples` draws, uniform in nominal x [1 - spread, 1 + spread], of the plant's masses and
    lengths (and, with motors, each motor's R, L, km, kb); every draw is run with each mode from
    the initial state (alpha1, alpha2) = alpha0 at rest. The same seed gives the same draws, and
    a larger `samples` extends a smaller one."""
    base = nominal(paths, system)
    rng = np.random.default_rng(seed)
    specs = []
    for _ in range(samples):
        factors = rng.uniform(1 - spread, 1 + spread, size=len(base))
        drawn = {k: float(v * f) for (k, v), f in zip(base.items(), factors)}
        for mode in modes:
            start = {"controller.mode": int(mode), "pendulum.alpha1_0": alpha0[0], "pendulum.alpha2_0": alpha0[1], **drawn}
            specs.append(make_spec(system, start, stop_time, step, criteria))
    return specs
