"""Work-precision of the plant's integrator, with scipy's integrators beside it, in one run.

    .venv/bin/python bench/python/work_precision.py [--quick] [--json out.json]

Problem: equations (6)-(7) with no torque, from x0 = (alpha1, omega1, alpha2, omega2) =
(0.5, 0, -0.3, 0) [rad, rad/s] to t = 1 s: the double pendulum falls and swings.
Reference: scipy DOP853 at rtol = atol = 1e-13 on tests/python/paper_model.py (written from the
paper, independently of the Rust code); its own error is estimated against rtol = atol = 1e-12.
Error = max over the four states of |x(1 s) - x_ref(1 s)|.

Rows: rustfmu's Dopri5 over [0, 1 s] in one call; the Pendulum model's do_step at h = 1 ms (what
the FMU does); fixed-step RK4 with as many right-hand-side evaluations as the one-call Dopri5;
scipy solve_ivp DOP853, RK45, LSODA. Rust rows are timed in Rust (median of repeats), scipy rows in
Python: scipy's time is mostly the interpreter calling the Python right-hand side, so compare its
evaluations, not its seconds.
"""

import argparse
import json
import pathlib
import subprocess
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "python"))
import paper_model  # noqa: E402

X0 = [0.5, 0.0, -0.3, 0.0]
T_END = 1.0


def reference():
    tight = paper_model.reference(X0, [0.0, T_END], rtol=1e-13, atol=1e-13)[-1]
    looser = paper_model.reference(X0, [0.0, T_END], rtol=1e-12, atol=1e-12)[-1]
    return tight, float(np.max(np.abs(tight - looser)))


def rust_rows(ref, tols):
    cmd = [
        "cargo", "run", "--release", "-q", "-p", "rustfmu-bench", "--bin", "work-precision", "--",
        "--x0", ",".join(map(repr, X0)), "--t-end", repr(T_END),
        "--reference", ",".join(repr(float(v)) for v in ref),
        "--tols", ",".join(f"{t:e}" for t in tols),
    ]
    run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{run.stderr}")
    return [json.loads(line) for line in run.stdout.splitlines() if line.strip()]


def scipy_rows(ref, tols, method):
    rows = []
    f = lambda t, x: paper_model.rhs(x)  # noqa: E731
    for tol in tols:
        start = time.perf_counter()
        sol = solve_ivp(f, (0.0, T_END), X0, method=method, rtol=tol, atol=tol)
        seconds = time.perf_counter() - start
        if not sol.success:
            rows.append(dict(method=f"scipy {method}", tol=tol, error=float("nan"), rhs=sol.nfev,
                             accepted=None, rejected=None, seconds_per_simulated_second=seconds / T_END,
                             note=sol.message))
            continue
        rows.append(dict(
            method=f"scipy {method}", tol=tol, error=float(np.max(np.abs(sol.y[:, -1] - ref))), rhs=int(sol.nfev),
            accepted=len(sol.t) - 1, rejected=None, seconds_per_simulated_second=seconds / T_END,
        ))
    return rows


def table(rows):
    lines = [
        "| method | tol | error at 1 s | RHS evals | steps (acc/rej) | time per simulated s |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        steps = "" if r.get("accepted") is None else f"{r['accepted']}" + (
            f"/{r['rejected']}" if r.get("rejected") is not None else "")
        t = r["seconds_per_simulated_second"]
        t_str = f"{t * 1e6:.1f} µs" if t < 1e-3 else f"{t * 1e3:.2f} ms"
        lines.append(f"| {r['method']} | {r['tol']:.0e} | {r['error']:.2e} | {r['rhs']} | {steps} | {t_str} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two tolerances only (CI: proves the script runs)")
    ap.add_argument("--json", help="also write the rows to this file")
    args = ap.parse_args()
    tols = [1e-4, 1e-8] if args.quick else [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
    ref, ref_err = reference()
    rows = rust_rows(ref, tols)
    for method in ["DOP853", "RK45", "LSODA"]:
        rows += scipy_rows(ref, tols, method)
    rows.sort(key=lambda r: (r["method"], -r["tol"]))
    print(f"x0 = {X0}, t = {T_END} s; reference (DOP853 1e-13) x(1 s) = {[float(v) for v in ref]}")
    print(f"reference error estimate (|ref(1e-13) - ref(1e-12)|, max) = {ref_err:.1e}\n")
    print(table(rows))
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(dict(x0=X0, t_end=T_END, reference=list(map(float, ref)),
                                                           reference_error=ref_err, rows=rows), indent=1))


if __name__ == "__main__":
    main()
