"""The full composed demo: Controller -> two DCMotors -> Pendulum -> Controller, four FMU
instances in an fmpy master loop, 1 ms communication step, from alpha1 = 0.1, alpha2 = -0.05 rad.
Writes composed_demo.csv (every communication point) and composed_demo.png.

Usage: python examples/composed_demo.py [--out DIR] [--fmu-dir target/fmu] [--stop 8] [--fmi-version 2|3]

--fmi-version 3 runs the FMI 3.0 FMUs (<fmu-dir>/fmi3/<id>.fmu, fmpy's FMU3Slave) instead of the
FMI 2.0 ones (<fmu-dir>/<id>.fmu, the default): the same loop, the same numbers to rounding
(docs/fmi3.md).
"""

import argparse
import csv
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from cosim import plant_motors_controller, simulate  # noqa: E402

RECORD = {
    "pendulum": ["alpha1", "omega1", "alpha2", "omega2"],
    "controller": ["M1", "M2", "U1", "U2"],
    "motor1": ["tau", "i"],
    "motor2": ["tau", "i"],
}
UNITS = {"alpha": "rad", "omega": "rad/s", "M": "N.m", "U": "V", "tau": "N.m", "i": "A", "time": "s"}


def unit(column):
    var = column.split(".")[-1]
    return next(u for prefix, u in sorted(UNITS.items(), key=lambda kv: -len(kv[0])) if var.startswith(prefix))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out")
    parser.add_argument("--fmu-dir", default="target/fmu")
    parser.add_argument("--stop", type=float, default=8.0)
    parser.add_argument("--fmi-version", choices=("2", "3"), default="2",
                        help="run the FMI 2.0 FMUs (<fmu-dir>/<id>.fmu, default) or the FMI 3.0 ones (<fmu-dir>/fmi3/<id>.fmu)")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fmus = pathlib.Path(args.fmu_dir)
    where = fmus / "fmi3" if args.fmi_version == "3" else fmus
    paths = [where / f"{n}.fmu" for n in ("Pendulum", "Controller", "DCMotor")]
    missing = [str(p) for p in paths if not p.exists()]
    if missing:
        sys.exit(f"missing {', '.join(missing)}: run `cargo run --release -p fmu-build` first")
    # The system comes from the SSP file next to the 2.0 FMUs (the same for both versions).
    system = plant_motors_controller(*map(str, paths), ssp=fmus / "PendulumMotors.ssp")
    r = simulate(system, args.stop, 1e-3, RECORD)

    columns = list(r)
    with open(out / "composed_demo.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([f"{c} [{unit(c)}]" for c in columns])
        w.writerows(np.column_stack([r[c] for c in columns]).tolist())

    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    t = r["time"]
    axes[0].plot(t, r["pendulum.alpha1"], label="α1")
    axes[0].plot(t, r["pendulum.alpha2"], label="α2")
    axes[0].set_ylabel("angle [rad]")
    axes[1].plot(t, r["controller.U1"], label="U1")
    axes[1].plot(t, r["controller.U2"], label="U2")
    axes[1].set_ylabel("motor voltage [V]")
    axes[2].plot(t, r["motor1.tau"], label="τ1 = M1")
    axes[2].plot(t, r["motor2.tau"], label="τ2 = M2")
    axes[2].set_ylabel("joint torque [N·m]")
    axes[2].set_xlabel("time t [s]")
    for ax in axes:
        ax.grid(True)
        ax.legend(loc="upper right")
    version = ", FMI 3.0 FMUs" if args.fmi_version == "3" else ""
    axes[0].set_title(f"Pendulum + 2 DC motors (200:1, 6 V) + LQR/PID controller, 1 ms steps{version}")
    fig.tight_layout()
    fig.savefig(out / "composed_demo.png", dpi=120)
    plt.close(fig)
    print(f"wrote {out / 'composed_demo.csv'} and {out / 'composed_demo.png'} (FMI {args.fmi_version}.0 FMUs from {where})")
    print(f"final angles: alpha1 = {r['pendulum.alpha1'][-1]:.2e} rad, alpha2 = {r['pendulum.alpha2'][-1]:.2e} rad")


if __name__ == "__main__":
    main()
