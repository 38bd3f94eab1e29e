"""Parameter studies of the closed loop on Dask: region of attraction, Monte Carlo robustness,
and a throughput benchmark.

    python examples/parameter_study.py roa    --out out/study [--n 21 --amax 0.6]
    python examples/parameter_study.py robust --out out/study [--samples 200 --spread 0.2]
    python examples/parameter_study.py bench  --out out/study [--runs 64 --workers 1 2]

Every run is one task on a Dask LocalCluster (--workers, --threads); --scheduler tcp://host:8786
runs the same study on an existing cluster. --master native (the default) runs each closed loop
in-process in the native SSP runner (the rustfmu_runner module, tests/setup-env.sh builds it);
--master isolated the same with each FMU in a child process (an FMU that crashes or hangs fails
its own run's row with component, function and time; the worker goes on), --master
isolated-system with the whole loop in one child process (the same errors, at the in-process
cost per step); --master fmpy in the
fmpy master, the reference: all give the same rows.
Rows go to <out>/<study>.csv as runs finish; running
the same command again skips the runs already there (resume). The PNG is drawn at the end.
FMUs come from target/fmu (build them with `cargo run --release -p fmu-build`).
"""

from __future__ import annotations

import argparse
import os
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

from pendulum_study import plots, studies  # noqa: E402
from pendulum_study.closed_loop import Criteria  # noqa: E402
from pendulum_study.runner import run_sequential, run_study  # noqa: E402


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="out/study", help="output directory (CSV and PNG)")
    p.add_argument("--fmu-dir", default=str(ROOT / "target" / "fmu"), help="where Pendulum.fmu, Controller.fmu, DCMotor.fmu are")
    p.add_argument("--scheduler", help="address of an existing Dask scheduler, e.g. tcp://10.0.0.5:8786 (default: a LocalCluster)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster workers (processes)")
    p.add_argument("--threads", type=int, default=1, help="threads per LocalCluster worker")
    p.add_argument("--stop-time", type=float, default=None, help="horizon of each run, s (roa: 10, robust, bench: 5)")
    p.add_argument("--step", type=float, default=None, help="communication step, s (roa: 0.01; robust, bench: 0.001, see docs/parameter-studies.md)")
    p.add_argument("--band", type=float, default=Criteria.band, help="settled when |alpha1|, |alpha2| stay within this, rad")
    p.add_argument("--hold", type=float, default=Criteria.hold, help="stabilized when settled at least this long before the end, s")
    p.add_argument("--retry-failed", action="store_true", help="on resume, run again the runs that failed")
    p.add_argument("--master", choices=("native", "isolated", "isolated-system", "fmpy"), default="native", help="native: the SSP runner in-process (default); isolated: the same, each FMU in a child process (a crash or hang fails its run's row, not the worker); isolated-system: the whole loop in one child process (the same, at the in-process cost per step); fmpy: the fmpy master (the reference)")
    p.add_argument("--no-progress", action="store_true")


def _modes(text: str) -> tuple[int, ...]:
    return tuple(int(m) for m in text.split(","))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="study", required=True)
    roa = sub.add_parser("roa", help="region of attraction: grid of initial angles, LQR and PID")
    _common(roa)
    roa.add_argument("--n", type=int, default=29, help="grid points per angle")
    roa.add_argument("--amax", type=float, default=1.4, help="initial angles in [-amax, amax], rad")
    roa.add_argument("--modes", type=_modes, default=(1, 2), help="controller modes (1 LQR, 2 PID, 3 LQR+PID)")
    roa.add_argument("--system", choices=("torque", "motors"), default="torque")
    rob = sub.add_parser("robust", help="Monte Carlo: plant and motor parameters within +-spread")
    _common(rob)
    rob.add_argument("--samples", type=int, default=200, help="parameter draws (each run with every mode)")
    rob.add_argument("--spread", type=float, default=0.2, help="relative uncertainty: uniform in nominal x [1-s, 1+s]")
    rob.add_argument("--seed", type=int, default=1)
    rob.add_argument("--modes", type=_modes, default=(1, 3))
    rob.add_argument("--system", choices=("torque", "motors"), default="motors")
    bench = sub.add_parser("bench", help="throughput (runs/s) of the same robustness runs with each worker count")
    _common(bench)
    bench.add_argument("--runs", type=int, default=64)
    bench.add_argument("--counts", type=int, nargs="+", default=[1, 2], help="worker counts to measure")
    bench.add_argument("--system", choices=("torque", "motors"), default="motors")
    args = parser.parse_args(argv)

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    paths = studies.fmu_paths(args.fmu_dir)
    for p in paths.values():
        if not pathlib.Path(p).exists():
            parser.error(f"{p} is missing: run `cargo run --release -p fmu-build` first")
    criteria = Criteria(band=args.band, hold=args.hold)
    if args.stop_time is None:
        args.stop_time = 10.0 if args.study == "roa" else 5.0
    if args.step is None:
        # Through the motors the PID limit-cycles on the voltage limit at 10 ms (the motors' step
        # of delay and the 10 ms derivative filter; docs/composition.md), settles at 5 ms and
        # below; the torque-driven loop settles at 10 ms.
        args.step = 0.01 if args.study == "roa" and args.system == "torque" else 0.001
    run = dict(fmu_paths=paths, scheduler=args.scheduler, threads_per_worker=args.threads, progress=not args.no_progress, retry_failed=args.retry_failed, master=args.master)

    if args.study == "roa":
        specs = studies.region_of_attraction(args.modes, args.n, args.amax, args.system, args.stop_time, args.step, criteria)
        csv = out / "roa.csv"
        print(run_study(specs, csv, n_workers=args.workers, **run))
        plots.region_of_attraction(_only(plots.read(csv), specs), out / "roa.png")
        print(f"wrote {out / 'roa.png'}")
    elif args.study == "robust":
        specs = studies.robustness(paths, args.samples, args.spread, args.seed, args.modes, args.system, stop_time=args.stop_time, step=args.step, criteria=criteria)
        csv = out / "robust.csv"
        print(run_study(specs, csv, n_workers=args.workers, **run))
        plots.robustness(_only(plots.read(csv), specs), out / "robust.png", args.spread)
        print(f"wrote {out / 'robust.png'}")
    else:
        # The same runs for every worker count, each into a fresh file (nothing to skip), and
        # once one after another in this process without Dask, for the overhead.
        specs = studies.robustness(paths, args.runs, 0.2, 1, (1,), args.system, stop_time=args.stop_time, step=args.step, criteria=criteria)
        print(f"{len(specs)} runs of the {args.system} system, horizon {args.stop_time:g} s, step {args.step:g} s, {args.master} master, on {os.cpu_count()} cores")
        t0, load0 = time.perf_counter(), os.getloadavg()[0]
        run_sequential(specs, paths, master=args.master)
        seq = len(specs) / (time.perf_counter() - t0)
        print(f"  no Dask, one after another: {seq:.2f} runs/s (load average {load0:.2f} -> {os.getloadavg()[0]:.2f})")
        results = {}
        for n in args.counts:
            csv = out / f"bench-{n}.csv"
            csv.unlink(missing_ok=True)
            load0 = os.getloadavg()[0]
            report = run_study(specs, csv, n_workers=n, **run)
            print(f"  {n} worker(s): {report} (load average {load0:.2f} -> {os.getloadavg()[0]:.2f})")
            results[n] = report.runs_per_second
        base = results[args.counts[0]]
        for n, r in results.items():
            print(f"workers={n}: {r:.2f} runs/s, speed-up {r / base:.2f} vs {args.counts[0]} worker(s)")
    return 0


def _only(df, specs):
    """The rows of this study's runs (the file may hold more from an earlier, larger one)."""
    from pendulum_study.runner import run_id

    ids = {run_id(s) for s in specs}
    return df[df["run_id"].isin(ids)]


if __name__ == "__main__":
    sys.exit(main())
