"""Draws the paper's Figures 6, 7 and 8 from the FMUs, as PNG files:

- fig6_open_loop.png: the Pendulum alone under M1 = M2 = 1 N.m from rest upright (diverges);
- fig7_stabilized.png: Pendulum + Controller (LQR + PID, torques), from alpha1 = 0.1, alpha2 = -0.05 rad;
- fig8_stabilized_motors.png: Pendulum + two DCMotors + Controller (voltages limited to 6 V).

Usage: python examples/paper_figures.py [--out DIR] [--fmu-dir target/fmu]
"""

import argparse
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from cosim import plant_and_controller, plant_motors_controller, simulate  # noqa: E402


def plot_angles(path, time, alpha1, alpha2, title):
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(time, alpha1, label="α1 (link 1)")
    ax.plot(time, alpha2, label="α2 (link 2)")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("angle from the upward vertical [rad]")
    ax.set_title(title)
    ax.grid(True)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out")
    parser.add_argument("--fmu-dir", default="target/fmu")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fmus = pathlib.Path(args.fmu_dir)
    pendulum, controller, motor = (str(fmus / f"{n}.fmu") for n in ("Pendulum", "Controller", "DCMotor"))

    r = simulate_fmu(
        pendulum, stop_time=1.5, step_size=1e-3, output_interval=1e-2, start_values={"M1": 1.0, "M2": 1.0}, output=["alpha1", "alpha2"]
    )
    plot_angles(out / "fig6_open_loop.png", r["time"], r["alpha1"], r["alpha2"], "Figure 6: open loop, M1 = M2 = 1 N·m")

    r = simulate(plant_and_controller(pendulum, controller, mode=3), 5.0, 1e-3, {"pendulum": ["alpha1", "alpha2"]})
    plot_angles(
        out / "fig7_stabilized.png", r["time"], r["pendulum.alpha1"], r["pendulum.alpha2"], "Figure 7: LQR + PID, torques applied directly"
    )

    r = simulate(plant_motors_controller(pendulum, controller, motor, mode=3), 5.0, 1e-3, {"pendulum": ["alpha1", "alpha2"]})
    plot_angles(
        out / "fig8_stabilized_motors.png",
        r["time"],
        r["pendulum.alpha1"],
        r["pendulum.alpha2"],
        "Figure 8: LQR + PID through two DC motors (200:1, 6 V)",
    )
    for name in ("fig6_open_loop", "fig7_stabilized", "fig8_stabilized_motors"):
        print(f"wrote {out / name}.png")


if __name__ == "__main__":
    main()
