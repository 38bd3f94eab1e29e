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
    step = np.diff(np.unique(df["pendulum.alpha1_0"]))
    size = (step.min() if len(step) else 0.1) * 0.95
    mesh = None
    for ax, mode in zip(axes, modes):
        d = df[df["controller.mode"] == mode]
        s = d[d["stabilized"]]
        mesh = ax.scatter(s["pendulum.alpha1_0"], s["pendulum.alpha2_0"], c=s["settling_time"], cmap="viridis", vmin=0, vmax=vmax, marker="s", s=_marker_area(ax, fig, size, d), linewidths=0)
        for outcome, marker, colour, label in (
            ("not_stabilized", "o", "tab:orange", "not settled in horizon"),
            ("fell", "x", "tab:red", "fell (|α| > π/2)"),
            ("failed", "X", "black", "run failed"),
        ):
            e = d[d["outcome"] == outcome]
            if len(e):
                ax.scatter(e["pendulum.alpha1_0"], e["pendulum.alpha2_0"], marker=marker, c=colour, s=18, label=f"{label} ({len(e)})")
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
    span = d["pendulum.alpha1_0"].max() - d["pendulum.alpha1_0"].min() + size
    width_pt = ax.get_position().width * fig.get_figwidth() * 72
    return max(4.0, (width_pt * size / span) ** 2 * 0.8)


def robustness(df: pd.DataFrame, path, spread: float) -> None:
    """Distributions, one colour per control law: settling time, peak motor voltage (the
    controller's command) and peak torque on the joints (what the motors deliver)."""
    modes = sorted(df["controller.mode"].unique())
    panels = [("settling_time", "settling time [s]", "Settling time (|α1|, |α2| ≤ band)", True)]
    if df["peak_voltage"].notna().any():
        panels.append(("peak_voltage", "peak |U| [V]", "Peak motor voltage command", False))
    panels.append(("peak_torque", "peak |M| [N·m]", "Peak torque on the joints", False))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.3))
    for ax, (col, xlabel, title, stabilized_only) in zip(axes, panels):
        d_all = df[df["stabilized"]] if stabilized_only else df
        values = d_all[col].dropna()
        bins = np.histogram_bin_edges(values, bins=40) if len(values) else 10
        for mode in modes:
            d = df[df["controller.mode"] == mode]
            shown = d[d["stabilized"]] if stabilized_only else d
            what = f"{len(shown)}/{len(d)} stabilized" if stabilized_only else f"{len(shown)} runs"
            ax.hist(shown[col].dropna(), bins=bins, alpha=0.6, label=f"{MODES.get(int(mode), mode)}: {what}")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("runs")
        ax.set_title(title)
        ax.legend(fontsize=8)
    n = len(df) // max(1, len(modes))
    fig.suptitle(f"Robustness: {n} plants drawn within ±{100 * spread:g} % of nominal; the controller keeps its nominal model")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
