"""Prints how the co-simulated plant + LQR loop approaches the linear closed loop A - BK
(equation (15)) as the communication step shrinks, from alpha1 = 1e-3, alpha2 = -5e-4 rad, with
the master evaluating each communication point in dependency order (Gauss-Seidel: the controller
sees the state of the same point; zero-order hold only) and in the old Jacobi order (every output
read before any input is set: one step of delay). Measure: max over 2 s of |alpha - alpha_linear|
(both angles) / max|x0|.

Usage: python examples/convergence.py [--fmu-dir target/fmu]
"""

import argparse
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from cosim import closed_loop_matrices, linear_response, plant_and_controller, simulate  # noqa: E402

K_NAMES = [f"K{i}{j}" for i in (1, 2) for j in (1, 2, 3, 4)]


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--fmu-dir", default="target/fmu")
    args = parser.parse_args()
    d = pathlib.Path(args.fmu_dir)
    x0 = np.array([1e-3, 0.0, -5e-4, 0.0])
    print("step h [s]   Gauss-Seidel (ratio)     Jacobi (ratio)")
    previous = {}
    for h in (8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4):
        row = f"{h:<12g}"
        for order in ("gauss-seidel", "jacobi"):
            system = plant_and_controller(str(d / "Pendulum.fmu"), str(d / "Controller.fmu"), alpha1=x0[0], alpha2=x0[2])
            r = simulate(system, 2.0, h, {"pendulum": ["alpha1", "alpha2"], "controller": K_NAMES}, order=order)
            k = np.array([r[f"controller.{n}"][-1] for n in K_NAMES]).reshape(2, 4)
            lin = linear_response(closed_loop_matrices(k)[2], x0, r["time"])
            err = max(np.abs(r["pendulum.alpha1"] - lin[:, 0]).max(), np.abs(r["pendulum.alpha2"] - lin[:, 2]).max())
            err /= np.abs(x0).max()
            ratio = "" if order not in previous else f"({previous[order] / err:.2f})"
            row += f" {err:<9.2e} {ratio:<14}"
            previous[order] = err
        print(row)


if __name__ == "__main__":
    main()
