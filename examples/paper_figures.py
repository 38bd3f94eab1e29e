"""Draws the paper's Figures 6, 7 and 8 from the FMUs, as PNG files, each titled with its
initial state and where it departs from the paper:

- fig6_open_loop.png: the paper's own setting, M1 = M2 = 1 N.m from rest upright (zero initial
  conditions). The paper drew it from the transfer functions (13), i.e. the linear model (12):
  that is panel (a); panel (b) is the nonlinear Pendulum FMU, which falls over, with the linear
  model while it stays within 1 rad.
- fig7_stabilized.png: Pendulum + Controller (LQR + PID, torques straight into the plant).
- fig8_stabilized_motors.png: the same through two DCMotor FMUs (200:1 gear, 6 V supply): the
  angles with Figure 7's, their difference, and what the motors add: voltages (commanded and
  applied), currents, and the joint torques they deliver against the torques the controller asks.

Figures 7 and 8 start from alpha1 = 0.1, alpha2 = -0.05 rad (the systems' values in
holonomic/systems.toml), not from the paper's "zero initial conditions": from rest upright the FMUs
stay there exactly, since nothing disturbs them (the paper attributes its deviations "only to
gravity", which does not move a pendulum at rest at its equilibrium). The master evaluates the
controller at the state of the same communication point (docs/composition.md), h = 1 ms.

Usage: python examples/paper_figures.py [--out DIR] [--fmu-dir target/fmu]
"""

import argparse
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from cosim import closed_loop_matrices, plant_and_controller, plant_motors_controller, simulate  # noqa: E402

START = "from α1 = 0.1, α2 = −0.05 rad at rest (paper: zero initial conditions)"
STEP = 1e-3
MOTOR_RECORD = {
    "pendulum": ["alpha1", "alpha2"],
    "controller": ["M1", "M2", "U1", "U2"],
    "motor1": ["tau", "i", "U_applied"],
    "motor2": ["tau", "i", "U_applied"],
}


def linear_open_loop(times, torque=(1.0, 1.0)):
    """The linear model (12) from x = 0 under constant torques: x(t) = ∫0^t e^(A s) ds B u."""
    a, b, _ = closed_loop_matrices(np.zeros((2, 4)))
    aug = np.zeros((5, 5))
    aug[:4, :4], aug[:4, 4] = a, b @ np.asarray(torque)
    return np.array([(scipy.linalg.expm(aug * t) @ np.r_[np.zeros(4), 1.0])[:4] for t in times])


def angles(ax, t, a1, a2, title, style="-", label=""):
    ax.plot(t, a1, style, label=f"α1{label}")
    ax.plot(t, a2, style, label=f"α2{label}")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("angle from the upward vertical [rad]")
    ax.set_title(title, fontsize=9)
    ax.grid(True)
    ax.legend(fontsize=8)


def over_time(ax, ylabel, title):
    """The axes of a panel over time: the time axis, `ylabel`, a small `title`."""
    ax.set(xlabel="time t [s]", ylabel=ylabel, title=title)
    ax.title.set_fontsize(9)


def save(fig, path, title):
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def figure6(out, pendulum):
    r = simulate_fmu(pendulum, stop_time=1.5, step_size=STEP, output_interval=1e-2, start_values={"M1": 1.0, "M2": 1.0}, output=["alpha1", "alpha2"])
    t = r["time"]
    lin = linear_open_loop(t)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    angles(left, t, lin[:, 0], lin[:, 2], "(a) linear model (12)/(13), as the paper plotted it")
    angles(right, t, r["alpha1"], r["alpha2"], "(b) nonlinear Pendulum FMU (eqs. (6)-(7)); dashed: (a) while |α| < 1 rad")
    near = np.abs(lin[:, [0, 2]]).max(axis=1) < 1.0
    right.set_prop_cycle(None)
    angles(right, t[near], lin[near, 0], lin[near, 2], right.get_title(), "--", " linear")
    save(fig, out / "fig6_open_loop.png", "Figure 6: open loop, M1 = M2 = 1 N·m from rest upright (x0 = 0, the paper's setting)")
    return {"time": t, "linear": lin, "alpha1": r["alpha1"], "alpha2": r["alpha2"]}


def figure7(out, pendulum, controller):
    r = simulate(plant_and_controller(pendulum, controller, mode=3), 5.0, STEP, {"pendulum": ["alpha1", "alpha2"], "controller": ["M1", "M2"]})
    fig, ax = plt.subplots(figsize=(7, 4))
    angles(ax, r["time"], r["pendulum.alpha1"], r["pendulum.alpha2"], "Pendulum + Controller FMUs, torques applied directly")
    save(fig, out / "fig7_stabilized.png", f"Figure 7: LQR + PID, {START}")
    return r


def figure8(out, pendulum, controller, motor, fig7):
    r = simulate(plant_motors_controller(pendulum, controller, motor, mode=3), 5.0, STEP, MOTOR_RECORD)
    t = r["time"]
    fig, axes = plt.subplots(2, 3, figsize=(15, 7.5))
    ax = axes[0, 0]
    angles(ax, t, r["pendulum.alpha1"], r["pendulum.alpha2"], "angles through the motors; dashed: Figure 7")
    ax.set_prop_cycle(None)
    ax.plot(t, fig7["pendulum.alpha1"], "--", t, fig7["pendulum.alpha2"], "--")
    ax = axes[0, 1]
    for n in ("alpha1", "alpha2"):
        ax.plot(t, 1e3 * (r[f"pendulum.{n}"] - fig7[f"pendulum.{n}"]), label=f"{n}: Fig. 8 − Fig. 7")
    over_time(ax, "[mrad]", "what the motors change in the angles")
    # The panels of both joints' signals: (axes, the times shown, curves (run, variable, style,
    # label) with {j} the joint, ylabel, title).
    whole, zoom = np.full(t.shape, True), t <= 0.3
    for ax, shown, curves, ylabel, title in [
        (axes[0, 2], whole, [(r, "controller.U{j}", "-", "U{j} commanded"), (r, "motor{j}.U_applied", ":", "U{j} applied (±6 V supply)")],
         "[V]", "motor voltages"),
        (axes[1, 0], whole, [(r, "motor{j}.i", "-", "i{j}")], "[A]", "armature currents"),
        (axes[1, 1], whole, [(r, "motor{j}.tau", "-", "τ{j} delivered to joint {j}"), (r, "controller.M{j}", "--", "M{j} asked by the controller")],
         "[N·m]", "joint torques"),
        (axes[1, 2], zoom, [(r, "motor{j}.tau", "-", "τ{j}"), (fig7, "controller.M{j}", "--", "M{j} of Figure 7")],
         "[N·m]", "first 0.3 s: torque limited by the 6 V supply vs Figure 7's"),
    ]:
        for j in (1, 2):
            for run, variable, style, label in curves:
                ax.plot(t[shown], run[variable.format(j=j)][shown], style, label=label.format(j=j))
        over_time(ax, ylabel, title)
    for ax in axes.flat[1:]:
        ax.grid(True)
        ax.legend(fontsize=7)
    save(fig, out / "fig8_stabilized_motors.png", f"Figure 8: LQR + PID through two DC motors (200:1 gear, B = 1e-6 N·m·s/rad, 6 V; paper: B = 9.0946, no gear), {START}")
    return r


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out")
    parser.add_argument("--fmu-dir", default="target/fmu")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fmus = pathlib.Path(args.fmu_dir)
    pendulum, controller, motor = (str(fmus / f"{n}.fmu") for n in ("Pendulum", "Controller", "DCMotor"))
    figure6(out, pendulum)
    fig7 = figure7(out, pendulum, controller)
    figure8(out, pendulum, controller, motor, fig7)
    for name in ("fig6_open_loop", "fig7_stabilized", "fig8_stabilized_motors"):
        print(f"wrote {out / name}.png")


if __name__ == "__main__":
    main()
