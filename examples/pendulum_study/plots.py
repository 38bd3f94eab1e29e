"""Pictures of a study's CSV: region of attraction and robustness (PNG, matplotlib Agg)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from .studies import MODES  # noqa: E402


def read(path) -> pd.DataFrame:
    return pd.read_csv(path)


def region_of_attraction(df: pd.DataFrame, path) -> None:
    """One panel per control law: initial (alpha1, alpha2) coloured by settling time; runs that
    did not stabilize within the horizon, that fell and that failed are marked."""
    modes = sorted(df["controller.mode"].unique())
    ok = df[df["stabilized"]]
    vmax = ok["settling_time"].max() if len(ok) else 1.0
    fig, axes = plt.subplots(1, len(modes), figsize=(5.2 * len(modes) + 1, 5.2), sharex=True, sharey=True, squeeze=False)
    axes = axes[0]
    step = np.diff(np.unique(df["pendulum.alpha1"]))
    size = (step.min() if len(step) else 0.1) * 0.95
    mesh = None
    for ax, mode in zip(axes, modes):
        d = df[df["controller.mode"] == mode]
        s = d[d["stabilized"]]
        mesh = ax.scatter(s["pendulum.alpha1"], s["pendulum.alpha2"], c=s["settling_time"], cmap="viridis", vmin=0, vmax=vmax, marker="s", s=_marker_area(ax, fig, size, d), linewidths=0)
        for outcome, marker, colour, label in (
            ("not_stabilized", "o", "tab:orange", "not settled in horizon"),
            ("fell", "x", "tab:red", "fell (|α| > π/2)"),
            ("failed", "X", "black", "run failed"),
        ):
            e = d[d["outcome"] == outcome]
            if len(e):
                ax.scatter(e["pendulum.alpha1"], e["pendulum.alpha2"], marker=marker, c=colour, s=18, label=f"{label} ({len(e)})")
        n_ok, n = len(s), len(d)
        ax.set_title(f"{MODES.get(int(mode), mode)} (mode {int(mode)}): {n_ok}/{n} stabilized")
        ax.set_xlabel("initial α1 [rad]")
        ax.set_aspect("equal")
        if any(d["outcome"] != "stabilized"):
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), fontsize=7, ncol=3)
    axes[0].set_ylabel("initial α2 [rad]")
    if mesh is not None:
        fig.colorbar(mesh, ax=list(axes), label="settling time [s]", shrink=0.9)
    horizon = df["stop_time"].iloc[0]
    system = df["system"].iloc[0]
    fig.suptitle(f"Region of attraction ({system} system, at rest initially, horizon {horizon:g} s)")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _marker_area(ax, fig, size, d) -> float:
    """Marker area (points^2) of a square about `size` data units wide on this grid."""
    span = d["pendulum.alpha1"].max() - d["pendulum.alpha1"].min() + size
    width_pt = ax.get_position().width * fig.get_figwidth() * 72
    return max(4.0, (width_pt * size / span) ** 2 * 0.8)


def robustness(df: pd.DataFrame, path, spread: float) -> None:
    """Settling time and peak voltage (or torque) distributions, one colour per control law."""
    modes = sorted(df["controller.mode"].unique())
    has_voltage = df["peak_voltage"].notna().any()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.3))
    for mode in modes:
        d = df[df["controller.mode"] == mode]
        s = d[d["stabilized"]]
        label = f"{MODES.get(int(mode), mode)}: {len(s)}/{len(d)} stabilized"
        a.hist(s["settling_time"], bins=30, alpha=0.6, label=label)
        peak = d["peak_voltage"] if has_voltage else d["peak_torque"]
        b.hist(peak.dropna(), bins=30, alpha=0.6, label=f"{MODES.get(int(mode), mode)} (all {len(d)} runs)")
    a.set_xlabel("settling time [s]")
    a.set_ylabel("runs")
    a.set_title("Settling time (|α1|, |α2| ≤ band)")
    a.legend(fontsize=8)
    b.set_xlabel("peak |U| [V]" if has_voltage else "peak |M| [N·m]")
    b.set_ylabel("runs")
    b.set_title("Peak motor voltage" if has_voltage else "Peak torque")
    b.legend(fontsize=8)
    n = len(df) // max(1, len(modes))
    fig.suptitle(f"Robustness: {n} plants drawn within ±{100 * spread:g} % of nominal; the controller keeps its nominal model")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

