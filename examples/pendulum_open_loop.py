"""Figure 6 of the paper: the open-loop double inverted pendulum under M1 = M2 = 1 N.m from rest.

Simulates target/fmu/Pendulum.fmu with fmpy and writes out/figure6_open_loop.{csv,png}.
Run `cargo run --release -p fmu-build` first (examples/run.sh does).
"""

import argparse
import pathlib

import fmpy
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--fmu", default=str(ROOT / "target" / "fmu" / "Pendulum.fmu"))
    ap.add_argument("--out", default=str(ROOT / "out"))
    ap.add_argument("--stop-time", type=float, default=1.5)
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    torques = np.array([(0.0, 1.0, 1.0)], dtype=[("time", float), ("M1", float), ("M2", float)])
    r = fmpy.simulate_fmu(args.fmu, stop_time=args.stop_time, output_interval=1e-3, input=torques)
    fmpy.write_csv(str(out / "figure6_open_loop.csv"), r)

    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(r["time"], r["alpha1"], label="α1 (link 1)")
    ax.plot(r["time"], r["alpha2"], label="α2 (link 2)")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("angle from upward vertical [rad]")
    ax.set_title("Figure 6: open loop, M1 = M2 = 1 N·m from rest (Pendulum.fmu via fmpy)")
    ax.grid(True)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "figure6_open_loop.png", dpi=120)
    print(f"wrote {out / 'figure6_open_loop.png'} and .csv; alpha1({args.stop_time}) = {r['alpha1'][-1]:.4f} rad")


if __name__ == "__main__":
    main()
