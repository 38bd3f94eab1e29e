"""At which baud rate, sample period and bus load does the LQR of eq. (14) still stabilize the
pendulum over a CAN bus, and what does the bus's delay cost against the direct loop? (issue 55)

    python examples/ls_bus_study.py [--out out/ls_bus_study] [--stop 3] [--workers 2] [--quick]

Every point is one run of examples/ls_bus_loop.py (the CanSensor, CanController and two
CanMotorDrive FMUs on the CanBus, with the Pendulum and two DCMotors, from alpha1 = 0.1,
alpha2 = -0.05 rad at rest), sensor and ECU at the same period, with the bus's background load
(frames of identifier 0, which win every arbitration, taking that share of the bus); and one run
of the direct loop (the SampledController wired to the plant) per period.

Stabilizes: the pendulum never falls (|alpha_i| <= pi/2), and the largest |alpha_i| over the
last second is below 0.01 rad (a tenth of the initial 0.1 rad) or below half the largest of the
second before (still decaying, by at least a factor 2 a second); and the bus keeps up with the
loop (its load below 0.99: on a saturated bus the frames that lose the arbitration queue without
end, so the measurement the ECU gets is older and older, and a run that still settles in its 3 s
would fall in a longer one). The same criterion (without the bus) judges the
direct loop at each period: with its one sample of delay the sampled LQR itself stops
stabilizing between 60 and 70 ms (at 70 ms it keeps swinging at 0.3 rad). For each point: the delay the bus adds to the loop (how much older the
measurement behind each command is when the command reaches its motor than in the direct loop,
where it is one period: mean and max), the command frames' latency, the bus load, the largest
angle difference from the direct loop, and the cost J = int (alpha1^2 + alpha2^2) dt against the
direct loop's.

Writes <out>/table.csv, <out>/table.md, <out>/stability_map.png (period x baud rate, one panel a
load) and <out>/networked_loop.png (angles, frame latencies, bus load of three points). FMUs come
from target/fmu/fmi3 (`cargo run --release -p fmu-build`).
"""

import argparse
import csv
import math
import multiprocessing
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import ls_bus_loop as L  # noqa: E402

BAUDS = [125_000, 250_000, 500_000, 1_000_000]
PERIODS = [0.002, 0.005, 0.01, 0.02, 0.05, 0.06, 0.07]
LOADS = [0.0, 0.5, 0.8]
# The points whose time series are drawn: near the direct loop, delayed by a loaded slow bus,
# and a bus the loop overloads.
SHOWN = [(1_000_000, 0.01, 0.0), (125_000, 0.05, 0.8), (125_000, 0.002, 0.5)]
SETTLED = 0.01  # rad


def stabilizes(fallen, late, before):
    """The criterion of the module's doc."""
    return bool(not fallen and (late < SETTLED or late < 0.5 * before))


def late_and_before(run, stop):
    a = np.abs(run.x[:, [0, 2]])
    return a[run.t >= stop - 1.0].max(), a[(run.t >= stop - 2.0) & (run.t < stop - 1.0)].max()


def cost(run):
    a = run.x[:, [0, 2]]
    return float(np.trapezoid((a ** 2).sum(axis=1), run.t))


def one(args):
    baud, period, load, stop, fmu_dir = args
    cfg = L.Config(stop=stop, sensor_period=period, ecu_period=period, baud=baud, background_load=load)
    t0 = time.time()
    run = L.networked(cfg, fmu_dir)
    late, before = late_and_before(run, stop) if not run.fallen else (math.inf, math.inf)
    added = L.added_delay(run, period)
    commands = [f.latency for f in run.frames if f.id in (L.MOTOR1_ID, L.MOTOR2_ID) and not math.isnan(f.arrived)]
    keeps_up = run.bus_load[-1] < 0.99
    row = dict(baud=baud, period=period, load=load, stable=stabilizes(run.fallen, late, before) and keeps_up,
               fallen=run.fallen, late_max_angle=late,
               added_delay_mean=float(added.mean()) if len(added) else math.inf,
               added_delay_max=float(added.max()) if len(added) else math.inf,
               command_latency_max=max(commands) if commands else math.inf,
               bus_load=float(run.bus_load[-1]), cost=cost(run), seconds=time.time() - t0)
    keep = (baud, period, load) in SHOWN
    series = dict(t=run.t, x=run.x, load=run.bus_load,
                  frames=[(f.id, f.sent, f.latency) for f in run.frames]) if keep else None
    return row, series


def direct_one(args):
    period, stop, fmu_dir = args
    d = L.direct(period, np.arange(0.0, stop + 1e-9, 1e-3), fmu_dir)
    return period, d


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="out/ls_bus_study")
    p.add_argument("--stop", type=float, default=3.0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--fmu-dir", default=str(L.FMU_DIR))
    p.add_argument("--quick", action="store_true", help="2 baud rates, 3 periods, 2 loads")
    a = p.parse_args()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    bauds, periods, loads = (([125_000, 1_000_000], [0.002, 0.01, 0.07], [0.0, 0.8]) if a.quick
                             else (BAUDS, PERIODS, LOADS))
    points = [(b, T, ld, a.stop, a.fmu_dir) for ld in loads for T in periods for b in bauds]
    t0 = time.time()
    with multiprocessing.Pool(a.workers) as pool:
        directs = dict(pool.map(direct_one, [(T, a.stop, a.fmu_dir) for T in periods]))
        results = pool.map(one, points)
    rows, shown = [], {}
    for (row, series), (b, T, ld, _, _) in zip(results, points):
        d = directs[T]
        row["cost_vs_direct"] = row["cost"] / cost(d)
        late, before = late_and_before(d, a.stop)
        row["direct_late_max_angle"] = float(late)
        row["direct_stable"] = stabilizes(False, late, before)
        rows.append(row)
        if series is not None:
            shown[(b, T, ld)] = series
    write_table(out, rows)
    draw_map(out, rows, bauds, periods, loads)
    if shown:
        draw_series(out, shown, directs)
    print(f"{len(rows)} runs in {time.time() - t0:.0f} s; {sum(r['stable'] for r in rows)} stabilize; "
          f"wrote {out}/table.csv, table.md, stability_map.png" + (", networked_loop.png" if shown else ""))


def write_table(out, rows):
    keys = list(rows[0])
    with open(out / "table.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    lines = ["| load | period [ms] | baud [kbit/s] | stabilizes | max abs(alpha), last s [rad] | added delay mean / max [ms] "
             "| command latency max [ms] | bus load | J / J_direct | direct loop: stabilizes, max abs(alpha), last s |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ms = lambda v: "-" if not math.isfinite(v) else f"{1e3 * v:.3f}"  # noqa: E731
        late = "fell" if r["fallen"] else f"{r['late_max_angle']:.2e}"
        lines.append(f"| {r['load']:.1f} | {1e3 * r['period']:g} | {r['baud'] // 1000} | {'yes' if r['stable'] else 'NO'} "
                     f"| {late} | {ms(r['added_delay_mean'])} / {ms(r['added_delay_max'])} | {ms(r['command_latency_max'])} "
                     f"| {r['bus_load']:.2f} | {r['cost_vs_direct']:.3f} "
                     f"| {'yes' if r['direct_stable'] else 'NO'}, {r['direct_late_max_angle']:.2e} |")
    (out / "table.md").write_text("\n".join(lines) + "\n")


def draw_map(out, rows, bauds, periods, loads):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(loads), figsize=(5 * len(loads), 4.2), sharey=True)
    for ax, ld in zip(np.atleast_1d(axes), loads):
        for r in (r for r in rows if r["load"] == ld):
            x, y = periods.index(r["period"]), bauds.index(r["baud"])
            ax.scatter([x], [y], s=500, marker="s", color="tab:green" if r["stable"] else "tab:red")
            label = "fell" if r["fallen"] else (f"{1e3 * r['added_delay_mean']:.2f}" if math.isfinite(r["added_delay_mean"])
                                                else "-")
            ax.annotate(label, (x, y), ha="center", va="center", fontsize=6.5, color="white")
        ax.set_xticks(range(len(periods)), [f"{1e3 * T:g}" for T in periods])
        ax.set_yticks(range(len(bauds)), [f"{b // 1000}" for b in bauds])
        ax.set_xlabel("sample period of sensor and ECU [ms]")
        ax.set_title(f"background load {ld:.0%}")
        ax.set_xlim(-0.6, len(periods) - 0.4)
        ax.set_ylim(-0.6, len(bauds) - 0.4)
    np.atleast_1d(axes)[0].set_ylabel("baud rate [kbit/s]")
    fig.suptitle("LQR of eq. (14) over CAN: green stabilizes (decays, the bus keeping up); red does not; "
                 "label: mean delay the bus adds [ms]", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "stability_map.png", dpi=130)
    plt.close(fig)


def draw_series(out, shown, directs):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    colors = ["tab:blue", "tab:orange", "tab:red"]
    for c, ((b, T, ld), s) in zip(colors, sorted(shown.items(), key=lambda kv: SHOWN.index(kv[0]))):
        name = f"{b // 1000} kbit/s, {1e3 * T:g} ms, load {ld:.0%}"
        axes[0].plot(s["t"], s["x"][:, 0], color=c, label=f"alpha1, {name}")
        axes[0].plot(s["t"], s["x"][:, 2], color=c, ls="--", lw=0.8)
        frames = np.array([(sent, lat) for _, sent, lat in s["frames"] if math.isfinite(lat)])
        if len(frames):
            axes[1].plot(frames[:, 0], 1e3 * frames[:, 1], ".", ms=2, color=c, label=name)
        axes[2].plot(s["t"], s["load"], color=c, label=name)
    for T, d in directs.items():
        if T == 0.01:
            axes[0].plot(d.t, d.x[:, 0], color="k", lw=0.8, ls=":", label="alpha1, direct loop, 10 ms")
    axes[0].set_ylabel("angle [rad] (alpha2 dashed)")
    axes[0].set_ylim(-0.3, 0.3)
    axes[0].legend(fontsize=7)
    axes[1].set_ylabel("frame latency [ms]")
    axes[1].set_yscale("log")
    axes[1].legend(fontsize=7)
    axes[2].set_ylabel("bus load since the start")
    axes[2].set_xlabel("time [s]")
    axes[2].legend(fontsize=7)
    fig.suptitle("The networked pendulum: angles, each frame's latency at its send time, bus load", fontsize=10)
    fig.tight_layout()
    fig.savefig(out / "networked_loop.png", dpi=130)
    plt.close(fig)


if __name__ == "__main__":
    main()
