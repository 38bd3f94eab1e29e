"""The paper's digital controller with its sample rate as an FMI 3.0 clock: PendulumLQR (the
plant from alpha1 = 0.1, alpha2 = -0.05 rad, torques applied directly) closed by the
SampledController (target/fmu/fmi3/SampledController.fmu: a periodic input clock `sample` of
interval Ts = 10 ms, clocked measurements and torques), run by the project's master, which
activates the clock at its ticks; beside it the same loop with the 2.0 Controller's
`sampled = true`, which samples at the communication points. At h = Ts the two are the same loop:
the script prints their largest difference (0: bit for bit) and writes both to
clocked_controller.csv.

Usage: python examples/clocked_controller.py [--out DIR] [--fmu-dir target/fmu] [--stop 5]
"""

import argparse
import csv
import dataclasses
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from cosim import simulate  # noqa: E402
from cosim.systems import plant_and_controller  # noqa: E402

TS = 0.01
RECORD = {"pendulum": ["alpha1", "omega1", "alpha2", "omega2"], "controller": ["M1", "M2"]}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out")
    parser.add_argument("--fmu-dir", default="target/fmu")
    parser.add_argument("--stop", type=float, default=5.0)
    args = parser.parse_args()
    fmus = pathlib.Path(args.fmu_dir)
    pendulum = str(fmus / "fmi3" / "Pendulum.fmu")
    clocked = simulate(plant_and_controller(pendulum, str(fmus / "fmi3" / "SampledController.fmu")), args.stop, TS, RECORD)
    system = plant_and_controller(pendulum, str(fmus / "Controller.fmu"))
    system = dataclasses.replace(system, components=tuple(
        dataclasses.replace(c, start={**c.start, "sampled": True, "Ts": TS}) if c.name == "controller" else c
        for c in system.components))
    sampled = simulate(system, args.stop, TS, RECORD)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    keys = [k for k in clocked if k != "time"]
    with open(out / "clocked_controller.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time"] + [f"clocked.{k}" for k in keys] + [f"sampled.{k}" for k in keys])
        for i, t in enumerate(clocked["time"]):
            w.writerow([t] + [clocked[k][i] for k in keys] + [sampled[k][i] for k in keys])
    worst = max(float(np.max(np.abs(clocked[k] - sampled[k]))) for k in keys)
    print(f"wrote {out / 'clocked_controller.csv'}: PendulumLQR closed by the SampledController (FMI 3.0, a clock of "
          f"{TS * 1e3:g} ms) and by the 2.0 Controller with sampled = true, {args.stop:g} s at h = {TS:g} s")
    print(f"largest difference between the two loops: {worst:.3g} (states in rad, rad/s; torques in N.m); "
          f"final alpha1 = {clocked['pendulum.alpha1'][-1]:.2e} rad")
    if worst != 0.0:
        sys.exit("the clocked controller's loop differs from the sampled controller's")


if __name__ == "__main__":
    main()
