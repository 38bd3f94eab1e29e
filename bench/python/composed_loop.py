"""The composed loop through three Python-driven masters in one run, beside the native Rust one.

    .venv/bin/python bench/python/composed_loop.py [--quick] [--topology full|controller-plant] [--json out.json]

The loop (FMU instances, parameter and start values of every type, connections) comes from the
Rust table, `cargo run --release -p rustfmu-bench --bin composed-loop -- --topology-json`, which
derives it from the systems of `holonomic/systems.toml`, the same description `fmu-build` writes as
`target/fmu/<system>.ssp`. Masters, all fixed step h = 1 ms, Jacobi (outputs at t read, inputs
set, every FMU steps), the order fmpy.ssp and libcosim use, so that all make the same calls:

- native: the Rust master on the `fmi` crate (bench/src/master.rs), run with `--jacobi` (its
  default is the dependency order, docs/composition.md);
- fmpy loop: a hand-written master loop over fmpy's FMU2Slave, with the same call sequence as the
  native master and the project's fmpy master (examples/cosim/master.py): start values after
  instantiation, connections propagated once per instance in initialization mode;
- fmpy.ssp: fmpy.ssp.simulation.simulate_ssp on the system's SSP file written by fmu-build;
- libcosim: libcosimpy's CosimExecution on the same SSP file, one simulate_until call.

Share inside our FMUs: the native master's time for the same loop (fastest of 5 runs) is (nearly
all) time spent in the FMUs' functions, so share = native time / master's wall time. For the fmpy
loop it is also measured directly, by timing each FMU call (that includes ctypes' own cost per call).

Cross-check: native, fmpy loop and libcosim make the same calls, so they must end in the same
state to round-off (1e-9 of the largest state component). fmpy.ssp starts every connector at 0 and does not propagate in
initialization mode (the controller sees the true state one step late, the plant and the motors
get 0 in the first step): an O(h) difference at the start that the closed loop damps, printed
against the native master; to check that fmpy.ssp ran the same loop, the fmpy loop is run once
more starting the way fmpy.ssp starts, and the two must agree to round-off too.
"""

import argparse
import json
import pathlib
import shutil
import os
import subprocess
import sys
import time
import types

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
H = 1e-3


def cargo_bin(*args):
    # bench/quick.sh names the binary its one workspace build made (a `cargo run -p` there would
    # build the dependency tree again, with other features); run alone, cargo builds it.
    built = os.environ.get("RUSTFMU_COMPOSED_LOOP")
    if built:
        cmd = [built, *args]
    else:
        cmd = ["cargo", "run", "--release", "-q", "-p", "rustfmu-bench", "--bin", "composed-loop", "--", *args]
    run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{run.stderr}")
    return run.stdout


#: Masters that make the same calls agree to round-off: relative to the largest state component.
EXACT = 1e-9


class Loop:
    """The topology, with every name resolved against the FMUs' model descriptions."""

    def __init__(self, topo):
        from fmpy import read_model_description

        self.topo = topo
        self.md = {}
        for s in topo["slaves"]:
            if not pathlib.Path(s["path"]).exists():
                sys.exit(f"{s['path']} is missing: run `cargo run --release -p fmu-build` first")
            self.md[s["instance"]] = read_model_description(s["path"])
        if not pathlib.Path(topo["ssp"]).exists():
            sys.exit(f"{topo['ssp']} is missing: run `cargo run --release -p fmu-build` first")

    def var(self, instance, name):
        for v in self.md[instance].modelVariables:
            if v.name == name:
                return v
        have = ", ".join(v.name for v in self.md[instance].modelVariables)
        sys.exit(f"{instance} has no variable '{name}'; it has: {have}")

    def vr(self, instance, name):
        return self.var(instance, name).valueReference

    def starts(self):
        """((instance, name), type, value) of every parameter and start value, type checked."""
        out = []
        for (inst, name), (kind, value) in self.topo["start_values"]:
            declared = self.var(inst, name).type
            # An Enumeration travels as an Integer (fmi2SetInteger).
            if declared != kind and not (declared == "Enumeration" and kind == "Integer"):
                sys.exit(f"{inst}.{name} is {declared} in its model description, the loop gives a {kind}")
            out.append(((inst, name), kind, value))
        return out

    def connectors(self, instance):
        """(name, kind) of every variable of `instance` the loop reads or writes."""
        out = []
        for (a, b) in self.topo["connections"]:
            if a[0] == instance and (a[1], "output") not in out:
                out.append((a[1], "output"))
            if b[0] == instance and (b[1], "input") not in out:
                out.append((b[1], "input"))
        return out


def set_typed(slave, vr, kind, value):
    if kind == "Real":
        slave.setReal([vr], [float(value)])
    elif kind in ("Integer", "Enumeration"):
        slave.setInteger([vr], [int(value)])
    elif kind == "Boolean":
        slave.setBoolean([vr], [bool(value)])
    else:
        sys.exit(f"unsupported type {kind}")


def run_fmpy_loop(loop, n, timed_calls=False, like_fmpy_ssp=False):
    """A master loop over fmpy's FMU2Slave. Returns (wall s, s inside FMU calls or None, plant state).

    like_fmpy_ssp: start as fmpy.ssp does (no propagation in initialization mode, every input 0
    in the first step), to check that fmpy.ssp ran this loop."""
    from fmpy import extract
    from fmpy.fmi2 import FMU2Slave

    topo = loop.topo
    slaves, dirs = {}, []
    for s in topo["slaves"]:
        md = loop.md[s["instance"]]
        d = extract(s["path"])
        dirs.append(d)
        slaves[s["instance"]] = FMU2Slave(guid=md.guid, unzipDirectory=d,
                                          modelIdentifier=md.coSimulation.modelIdentifier,
                                          instanceName=s["instance"])
    starts = loop.starts()
    for i, f in slaves.items():
        f.instantiate()
        for (inst, name), kind, value in starts:
            if inst == i:
                set_typed(f, loop.vr(inst, name), kind, value)
        f.setupExperiment(startTime=0.0, stopTime=n * H)
    for f in slaves.values():
        f.enterInitializationMode()

    outs = {i: [loop.vr(i, n_) for n_, k in loop.connectors(i) if k == "output"] for i in slaves}
    ins = {i: [loop.vr(i, n_) for n_, k in loop.connectors(i) if k == "input"] for i in slaves}
    out_names = {i: [n_ for n_, k in loop.connectors(i) if k == "output"] for i in slaves}
    in_names = {i: [n_ for n_, k in loop.connectors(i) if k == "input"] for i in slaves}
    links = [((a[0], out_names[a[0]].index(a[1])), (b[0], in_names[b[0]].index(b[1]))) for a, b in topo["connections"]]
    in_values = {i: [0.0] * len(ins[i]) for i in slaves}

    def exchange():
        out_values = {i: f.getReal(outs[i]) if outs[i] else [] for i, f in slaves.items()}
        for (fi, fj), (ti, tj) in links:
            in_values[ti][tj] = out_values[fi][fj]
        for i, f in slaves.items():
            if ins[i]:
                f.setReal(ins[i], in_values[i])

    if not like_fmpy_ssp:
        for _ in slaves:
            exchange()
    for f in slaves.values():
        f.exitInitializationMode()

    inside = 0.0
    clock = time.perf_counter
    start = clock()
    for k in range(n):
        t = k * H
        if like_fmpy_ssp and k == 0:
            for i, f in slaves.items():
                if ins[i]:
                    f.setReal(ins[i], [0.0] * len(ins[i]))
            for f in slaves.values():
                f.doStep(currentCommunicationPoint=t, communicationStepSize=H)
            continue
        if not timed_calls:
            exchange()
            for f in slaves.values():
                f.doStep(currentCommunicationPoint=t, communicationStepSize=H)
            continue
        out_values = {}
        for i, f in slaves.items():
            if outs[i]:
                c0 = clock(); out_values[i] = f.getReal(outs[i]); inside += clock() - c0
        for (fi, fj), (ti, tj) in links:
            in_values[ti][tj] = out_values[fi][fj]
        for i, f in slaves.items():
            if ins[i]:
                c0 = clock(); f.setReal(ins[i], in_values[i]); inside += clock() - c0
        for f in slaves.values():
            c0 = clock(); f.doStep(currentCommunicationPoint=t, communicationStepSize=H); inside += clock() - c0
    wall = clock() - start
    plant = topo["plant"]
    x = slaves[plant].getReal([loop.vr(plant, s) for s in topo["states"]])
    for f in slaves.values():
        f.terminate()
        f.freeInstance()
    for d in dirs:
        shutil.rmtree(d, ignore_errors=True)
    return wall, (inside if timed_calls else None), list(x)


def run_fmpy_ssp(loop, n):
    """fmpy.ssp on the system's SSP file. simulate_ssp does not apply the SSD's ParameterBindings
    (only its `parameter_set` argument), so the same values are passed there, typed."""
    import fmpy.ssp.simulation as sim

    topo = loop.topo
    params = types.SimpleNamespace(parameters=[
        types.SimpleNamespace(name=f"{inst}.{name}", value=value) for (inst, name), _, value in loop.starts()
    ])
    start = time.perf_counter()
    # fmpy.ssp loops `while time < stop_time` on a running sum: stop half a step early so it
    # takes exactly n steps.
    result = sim.simulate_ssp(topo["ssp"], start_time=0.0, stop_time=(n - 0.5) * H, step_size=H,
                              parameter_set=params)
    wall = time.perf_counter() - start
    if len(result) != n:
        sys.exit(f"fmpy.ssp took {len(result)} steps, expected {n}")
    return wall, [float(result[f"{topo['plant']}.{s}"][-1]) for s in topo["states"]]


def run_libcosim(loop, n):
    """libcosim's fixed-step algorithm on the system's SSP file, in one simulate_until call.
    libcosim applies the SSD's parameter values itself (the Pendulum's initial state is its
    parameters alpha1_0..omega2_0); every start value is given again through *_initial_value,
    the same values, so that the run does not depend on which bindings libcosim applies."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    topo = loop.topo
    h_ns = int(round(H * 1e9))
    ex = CosimExecution.from_ssp_file(topo["ssp"], step_size=h_ns)
    index = {i.name.decode(): i.index for i in ex.slave_infos()}
    ignored = []
    for (inst, name), kind, value in loop.starts():
        if loop.var(inst, name).type == "Enumeration":
            # libcosim ignores FMI 2.0 Enumeration variables ("variable with name mode will be
            # ignored"): it runs with the FMU's default.
            ignored.append(f"{inst}.{name}")
            continue
        setter = {"Real": ex.real_initial_value, "Integer": ex.integer_initial_value,
                  "Boolean": ex.boolean_initial_value}[kind]
        if not setter(index[inst], loop.vr(inst, name), value):
            sys.exit(f"libcosim refused the initial value {inst}.{name} = {value}")
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    plant = index[topo["plant"]]
    states = [loop.vr(topo["plant"], s) for s in topo["states"]]
    start = time.perf_counter()
    ok = ex.simulate_until(n * h_ns)
    wall = time.perf_counter() - start
    if not ok:
        sys.exit("libcosim: the simulation failed")
    return wall, list(observer.last_real_values(plant, states)), ignored


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0.2 s of simulated time (CI: proves the script runs)")
    ap.add_argument("--topology", help="full (default) or controller-plant")
    ap.add_argument("--json", help="also write the results to this file")
    args = ap.parse_args()
    seconds = 0.2 if args.quick else 10.0
    n = int(round(seconds / H))
    sel = ["--topology", args.topology] if args.topology else []
    topo = json.loads(cargo_bin(*sel, "--topology-json"))
    loop = Loop(topo)
    print(f"loop: {topo['name']} (system {topo['system']}, {pathlib.Path(topo['ssp']).name}): {topo['description']}")
    print(f"{seconds:g} s at h = {H * 1e3:g} ms ({n} steps)\n")

    native = json.loads(cargo_bin(*sel, "--seconds", str(seconds), "--repeat", "5", "--jacobi"))
    # The FMUs' own time: the native master's fastest of 5 runs (least disturbed by other load).
    t_fmu = native["wall_best_s"]
    rows = [dict(master="native Rust (fmi crate), fastest of 5", wall=t_fmu, share=1.0, measured_share=None,
                 final=native["final_state"], tol=0.0)]
    wall, _, x = run_fmpy_loop(loop, n)
    _, inside, _ = run_fmpy_loop(loop, n, timed_calls=True)
    rows.append(dict(master="fmpy master loop (FMU2Slave)", wall=wall, share=t_fmu / wall, measured_share=inside / wall,
                     final=x, tol=EXACT))
    wall, x = run_fmpy_ssp(loop, n)
    rows.append(dict(master="fmpy.ssp simulate_ssp (SSP file)", wall=wall, share=t_fmu / wall, measured_share=None,
                     final=x, tol=None))
    _, _, like_ssp = run_fmpy_loop(loop, n, like_fmpy_ssp=True)
    ssp_vs_replica = float(np.max(np.abs(np.array(x) - np.array(like_ssp))))
    wall, x, ignored = run_libcosim(loop, n)
    rows.append(dict(master="libcosim (libcosimpy, same SSP file)", wall=wall, share=t_fmu / wall,
                     measured_share=None, final=x, tol=None if ignored else EXACT,
                     note=f" (libcosim ignores Enumerations: ran {', '.join(ignored)} at its default; not compared)"
                     if ignored else None))

    ref = np.array(rows[0]["final"])
    for r in rows:
        r["diff"] = float(np.max(np.abs(np.array(r["final"]) - ref)))
    print("| master | wall time | real-time factor | share inside our FMUs (native time / wall) "
          "| share, FMU calls timed | final state vs native |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        measured = "" if r["measured_share"] is None else f"{100 * r['measured_share']:.0f} % (incl. ctypes)"
        diff = "" if r is rows[0] else f"{r['diff']:.1e}"
        if r.get("note"):
            diff += r["note"]
        elif r["tol"] is None:
            diff += f" (starts differently; vs the fmpy loop started alike: {ssp_vs_replica:.1e})"
        print(f"| {r['master']} | {r['wall'] * 1e3:.1f} ms | {seconds / r['wall']:.0f} | {100 * r['share']:.1f} % "
              f"| {measured} | {diff} |")
    print(f"\nfinal plant state per master ({', '.join(topo['states'])}):")
    for r in rows:
        print(f"  {r['master']}: {r['final']}")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(dict(topology=topo, seconds=seconds, rows=rows), indent=1))
    # Every master ran the same loop: the same final state (fmpy.ssp: as the same loop started alike).
    scale = float(np.max(np.abs(ref)))
    if not ssp_vs_replica <= EXACT * scale:
        sys.exit(f"fmpy.ssp ends at {rows[2]['final']}, the fmpy loop started as fmpy.ssp starts at {like_ssp}: "
                 f"differs by {ssp_vs_replica:.2e}, more than {EXACT:.0e} x {scale:.2e}: not the same loop")
    for r in rows[1:]:
        if r["tol"] is not None and not r["diff"] <= r["tol"] * scale:
            sys.exit(f"{r['master']} ends at {r['final']}, the native master at {ref.tolist()}: differs by "
                     f"{r['diff']:.2e}, more than {r['tol']:.0e} x {scale:.2e}: not the same loop")


if __name__ == "__main__":
    main()
