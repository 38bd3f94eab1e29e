"""The native runner's first-order hold (`input_derivatives=True`, issue 26) against its
zero-order hold, on the paper's two loops: the largest deviation of the pendulum's states over
2 s from (a) the linear closed loop x(t) = expm((A - BK) t) x0 of eqs. (12) and (14), as a
fraction of max|x0|, and (b) the same loop's own limit (the first-order hold at h = 10 µs), whose
ratio between halved steps gives the convergence order.

    .venv/bin/python bench/python/first_order_hold.py

From x0 = (1e-3, 0, -5e-4, 0) for PendulumLQR (where the linear loop is a fair reference), from
the SSP file's start for PendulumMotors (deviation (b) only). Needs target/fmu/*.ssp and the
rustfmu_runner module (tests/setup-env.sh installs it).
"""

import pathlib

import numpy as np
import scipy.linalg

import rustfmu_runner

ROOT = pathlib.Path(__file__).resolve().parents[2]
A = np.array([[0.0, 1.0, 0.0, 0.0], [44.145, 0.0, -14.715, 0.0], [0.0, 0.0, 0.0, 1.0], [-44.145, 0.0, 29.43, 0.0]])
B = np.array([[0.0, 0.0], [6.0, -6.0], [0.0, 0.0], [-6.0, 12.0]])
K = np.array([[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]])
X0 = np.array([1e-3, 0.0, -5e-4, 0.0])
STATE = ["pendulum.alpha1", "pendulum.omega1", "pendulum.alpha2", "pendulum.omega2"]
STEPS = [8e-3, 4e-3, 2e-3, 1e-3, 5e-4]
FINE = 1e-5


def table(name, start, linear, scale):
    s = rustfmu_runner.System(str(ROOT / "target" / "fmu" / f"{name}.ssp"))
    ref = s.run(2.0, FINE, start=start, record=STATE, input_derivatives=True)
    print(f"\n{name}, 2 s, deviations as fractions of the initial deviation" + ("" if linear else " (the SSP file's start, 0.1 rad)"))
    print("| h | zero-order hold: from A - BK | first-order hold: from A - BK | ZOH: from the limit | FOH: from the limit | FOH order |")
    print("|---|---|---|---|---|---|")
    prev = None
    for h in STEPS:
        cells = []
        m = int(round(h / FINE))
        for d in (False, True):
            r = s.run(2.0, h, start=start, record=STATE, input_derivatives=d)
            x = np.column_stack([r[k] for k in STATE])
            own = max(np.abs(r[k] - ref[k][::m]).max() for k in STATE) / scale
            lin = None
            if linear:
                xl = np.array([scipy.linalg.expm((A - B @ K) * t) @ X0 for t in r["time"]])
                lin = np.abs(x - xl).max() / np.abs(X0).max()
            cells.append((lin, own))
        order = f"{np.log2(prev / cells[1][1]):.2f}" if prev else ""
        prev = cells[1][1]
        fmt = lambda v: "" if v is None else f"{v:.3e}"  # noqa: E731
        print(f"| {h * 1e3:g} ms | {fmt(cells[0][0])} | {fmt(cells[1][0])} | {cells[0][1]:.3e} | {cells[1][1]:.3e} | {order} |")


def main():
    table("PendulumLQR", {"pendulum.alpha1_0": X0[0], "pendulum.alpha2_0": X0[2]}, True, np.abs(X0).max())
    # PendulumMotors starts at alpha1 = 0.1 rad (its SSP file's parameter set).
    table("PendulumMotors", {}, False, 0.1)


if __name__ == "__main__":
    main()
