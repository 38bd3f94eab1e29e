"""The composed loop through three Python-driven masters in one run, beside the native Rust one.

    .venv/bin/python bench/python/composed_loop.py [--quick] [--topology NAME] [--json out.json]

The loop (which FMUs, which connections, start values, and, while no Controller FMU is
packaged, the stand-in LQR state feedback computed by the master) comes from the Rust table,
`cargo run --release -p rustfmu-bench --bin composed-loop -- --topology-json`, so every master
runs the same loop. Masters, all fixed step h = 1 ms, Jacobi (outputs at t read, inputs set,
every FMU steps):

- native: the Rust master on the `fmi` crate (bench/src/master.rs);
- fmpy loop: a hand-written master loop over fmpy's FMU2Slave;
- fmpy.ssp: fmpy.ssp.simulation.simulate_ssp on the SSP file written here;
- libcosim: libcosimpy's CosimExecution on the same SSP file.

Share inside our FMUs: the native master's time for the same loop (fastest of 5 runs) is (nearly
all) time spent in the FMUs' functions, so share = native time / master's wall time. For the fmpy loop it is also
measured directly, by timing each FMU call (that includes ctypes' own cost per call).

With the stand-in feedback, fmpy.ssp gets it by wrapping fmpy.ssp.simulation.do_step, and
libcosim by stepping one step at a time with an override manipulator: the controller runs in
Python there, and its cost is part of those masters' wall time.
"""

import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time
import types
import zipfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
H = 1e-3


def cargo_bin(*args):
    cmd = ["cargo", "run", "--release", "-q", "-p", "rustfmu-bench", "--bin", "composed-loop", "--", *args]
    run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{run.stderr}")
    return run.stdout


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
        self.fmu_of = {s["instance"]: s for s in topo["slaves"]}

    def vr(self, instance, name):
        for v in self.md[instance].modelVariables:
            if v.name == name:
                return v.valueReference
        have = ", ".join(v.name for v in self.md[instance].modelVariables)
        sys.exit(f"{instance} has no variable '{name}'; it has: {have}")

    def start(self, instance, name):
        """The value `name` has after initialization: the loop's start value, else the FMU's."""
        for (inst, n), value in self.topo["start_values"]:
            if (inst, n) == (instance, name):
                return value
        for v in self.md[instance].modelVariables:
            if v.name == name:
                return float(v.start)
        sys.exit(f"{instance} has no variable '{name}'")

    def connectors(self, instance, ssd=False):
        """(name, kind) of every variable of `instance` the loop reads or writes. In the SSD, the
        inputs the master's feedback drives are left out: fmpy.ssp wants every declared input
        connected, libcosim wants every connection between two elements, and the feedback sets
        them itself."""
        out = []
        for (a, b) in self.topo["connections"]:
            if a[0] == instance and (a[1], "output") not in out:
                out.append((a[1], "output"))
            if b[0] == instance and (b[1], "input") not in out:
                out.append((b[1], "input"))
        fb = self.topo["feedback"]
        if fb and fb["plant"] == instance:
            out += [(s, "output") for s in fb["states"] if (s, "output") not in out]
            if not ssd:
                out += [(u, "input") for u in fb["inputs"] if (u, "input") not in out]
        return out

    def write_ssp(self, path, stop_time):
        """An SSP 1.0 archive: SystemStructure.ssd and the FMUs under resources/."""
        comps = []
        for s in self.topo["slaves"]:
            conns = "".join(
                f'<ssd:Connector name="{n}" kind="{k}"><ssc:Real/></ssd:Connector>'
                for n, k in self.connectors(s["instance"], ssd=True)
            )
            comps.append(
                f'<ssd:Component name="{s["instance"]}" type="application/x-fmu-sharedlibrary" '
                f'source="resources/{s["fmu"]}.fmu"><ssd:Connectors>{conns}</ssd:Connectors></ssd:Component>'
            )
        connections = "".join(
            f'<ssd:Connection startElement="{a[0]}" startConnector="{a[1]}" endElement="{b[0]}" endConnector="{b[1]}"/>'
            for a, b in self.topo["connections"]
        )
        ssd = (
            '<?xml version="1.0" encoding="UTF-8"?>\n'
            '<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
            'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="composed_loop">'
            f'<ssd:System name="loop"><ssd:Elements>{"".join(comps)}</ssd:Elements>'
            + (f"<ssd:Connections>{connections}</ssd:Connections>" if connections else "")
            + f'</ssd:System><ssd:DefaultExperiment startTime="0" stopTime="{stop_time}"/>'
            "</ssd:SystemStructureDescription>"
        )
        with zipfile.ZipFile(path, "w") as z:
            z.writestr("SystemStructure.ssd", ssd)
            for fmu in {s["fmu"]: s["path"] for s in self.topo["slaves"]}.items():
                z.write(fmu[1], f"resources/{fmu[0]}.fmu")


def feedback_law(topo):
    fb = topo["feedback"]
    if not fb:
        return None
    K = np.array(fb["K"])
    return lambda x: -(K @ np.asarray(x))


def run_fmpy_loop(loop, n, timed_calls=False):
    """A master loop over fmpy's FMU2Slave. Returns (wall s, s inside FMU calls or None, plant state)."""
    from fmpy import extract
    from fmpy.fmi2 import FMU2Slave

    topo = loop.topo
    slaves, dirs = {}, []
    for s in topo["slaves"]:
        md = loop.md[s["instance"]]
        d = extract(s["path"])
        dirs.append(d)
        f = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=s["instance"])
        f.instantiate()
        f.setupExperiment(startTime=0.0, stopTime=n * H)
        f.enterInitializationMode()
        slaves[s["instance"]] = f
    for (inst, name), value in topo["start_values"]:
        slaves[inst].setReal([loop.vr(inst, name)], [value])
    for f in slaves.values():
        f.exitInitializationMode()

    outs = {i: [loop.vr(i, n_) for n_, k in loop.connectors(i) if k == "output"] for i in slaves}
    ins = {i: [loop.vr(i, n_) for n_, k in loop.connectors(i) if k == "input"] for i in slaves}
    out_names = {i: [n_ for n_, k in loop.connectors(i) if k == "output"] for i in slaves}
    in_names = {i: [n_ for n_, k in loop.connectors(i) if k == "input"] for i in slaves}
    links = [((a[0], out_names[a[0]].index(a[1])), (b[0], in_names[b[0]].index(b[1]))) for a, b in topo["connections"]]
    fb, law = topo["feedback"], feedback_law(topo)
    if fb:
        fb_states = [out_names[fb["plant"]].index(s) for s in fb["states"]]
        fb_inputs = [in_names[fb["plant"]].index(u) for u in fb["inputs"]]
    in_values = {i: [0.0] * len(ins[i]) for i in slaves}
    inside = 0.0
    clock = time.perf_counter
    start = clock()
    for k in range(n):
        t = k * H
        out_values = {}
        for i, f in slaves.items():
            if outs[i]:
                if timed_calls:
                    c0 = clock(); out_values[i] = f.getReal(outs[i]); inside += clock() - c0
                else:
                    out_values[i] = f.getReal(outs[i])
        for (fi, fj), (ti, tj) in links:
            in_values[ti][tj] = out_values[fi][fj]
        if fb:
            u = law([out_values[fb["plant"]][j] for j in fb_states])
            for j, v in zip(fb_inputs, u):
                in_values[fb["plant"]][j] = float(v)
        for i, f in slaves.items():
            if timed_calls:
                c0 = clock()
                if ins[i]:
                    f.setReal(ins[i], in_values[i])
                f.doStep(currentCommunicationPoint=t, communicationStepSize=H)
                inside += clock() - c0
            else:
                if ins[i]:
                    f.setReal(ins[i], in_values[i])
                f.doStep(currentCommunicationPoint=t, communicationStepSize=H)
    wall = clock() - start
    plant = "Pendulum"
    x = slaves[plant].getReal([loop.vr(plant, s) for s in ["alpha1", "omega1", "alpha2", "omega2"]])
    for f in slaves.values():
        f.terminate()
        f.freeInstance()
    for d in dirs:
        shutil.rmtree(d, ignore_errors=True)
    return wall, (inside if timed_calls else None), list(x)


def run_fmpy_ssp(loop, ssp, n):
    import fmpy.ssp.simulation as sim

    topo = loop.topo
    fb, law = topo["feedback"], feedback_law(topo)
    original = sim.do_step
    if fb:
        def do_step(component, t, h):
            if component.name == fb["plant"]:
                x = [sim.get_value(component, s) for s in fb["states"]]
                for name, value in zip(fb["inputs"], law(x)):
                    sim.set_value(component, name, value)
            original(component, t, h)
        sim.do_step = do_step
    params = types.SimpleNamespace(parameters=[
        types.SimpleNamespace(name=f"{inst}.{name}", value=value) for (inst, name), value in topo["start_values"]
    ])
    try:
        start = time.perf_counter()
        # fmpy.ssp loops `while time < stop_time` on a running sum: stop half a step early so it
        # takes exactly n steps.
        result = sim.simulate_ssp(str(ssp), start_time=0.0, stop_time=(n - 0.5) * H, step_size=H,
                                  parameter_set=params)
        wall = time.perf_counter() - start
    finally:
        sim.do_step = original
    cols = [c for c in result.dtype.names if c.endswith(("alpha1", "omega1", "alpha2", "omega2"))]
    return wall, len(result), {c: float(result[c][-1]) for c in cols}


def run_libcosim(loop, ssp, n):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver

    topo = loop.topo
    h_ns = int(round(H * 1e9))
    ex = CosimExecution.from_ssp_file(str(ssp), step_size=h_ns)
    index = {i.name.decode(): i.index for i in ex.slave_infos()}
    for (inst, name), value in topo["start_values"]:
        ex.real_initial_value(index[inst], loop.vr(inst, name), value)
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    fb, law = topo["feedback"], feedback_law(topo)
    plant = index["Pendulum"]
    states = [loop.vr("Pendulum", s) for s in ["alpha1", "omega1", "alpha2", "omega2"]]
    start = time.perf_counter()
    if fb:
        manipulator = CosimManipulator.create_override()
        ex.add_manipulator(manipulator)
        fb_states = [loop.vr(fb["plant"], s) for s in fb["states"]]
        fb_inputs = [loop.vr(fb["plant"], u) for u in fb["inputs"]]
        p = index[fb["plant"]]
        # The observer has values only once the execution ran: the first input comes from the
        # start values, every later one from the state the observer saw after the last step.
        x = [loop.start(fb["plant"], s) for s in fb["states"]]
        ok = True
        for _ in range(n):
            manipulator.slave_real_values(p, fb_inputs, [float(v) for v in law(x)])
            ok = ex.step(1) and ok
            x = observer.last_real_values(p, fb_states)
    else:
        ok = ex.simulate_until(n * h_ns)
    wall = time.perf_counter() - start
    if not ok:
        sys.exit("libcosim: the simulation failed")
    return wall, list(observer.last_real_values(plant, states))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0.2 s of simulated time (CI: proves the script runs)")
    ap.add_argument("--topology", help="stand-in, controller-plant or full (default: the richest packaged)")
    ap.add_argument("--json", help="also write the results to this file")
    args = ap.parse_args()
    seconds = 0.2 if args.quick else 10.0
    n = int(round(seconds / H))
    sel = ["--topology", args.topology] if args.topology else []
    topo = json.loads(cargo_bin(*sel, "--topology-json"))
    loop = Loop(topo)
    print(f"loop: {topo['name']}: {topo['description']}")
    print(f"{seconds:g} s at h = {H * 1e3:g} ms ({n} steps)\n")

    native = json.loads(cargo_bin(*sel, "--seconds", str(seconds), "--repeat", "5"))
    # The FMUs' own time: the native master's fastest of 5 runs (least disturbed by other load).
    t_fmu = native["wall_best_s"]
    rows = [dict(master="native Rust (fmi crate), fastest of 5", wall=t_fmu, share=1.0, measured_share=None,
                 final=native["final_state"])]
    wall, _, x = run_fmpy_loop(loop, n)
    _, inside, _ = run_fmpy_loop(loop, n, timed_calls=True)
    rows.append(dict(master="fmpy master loop (FMU2Slave)", wall=wall, share=t_fmu / wall, measured_share=inside / wall,
                     final=x))
    with tempfile.TemporaryDirectory() as tmp:
        ssp = pathlib.Path(tmp) / "composed_loop.ssp"
        loop.write_ssp(ssp, seconds)
        wall, steps, x = run_fmpy_ssp(loop, ssp, n)
        rows.append(dict(master="fmpy.ssp simulate_ssp", wall=wall, share=t_fmu / wall, measured_share=None,
                         final=x, steps=steps))
        wall, x = run_libcosim(loop, ssp, n)
        rows.append(dict(master="libcosim (libcosimpy, SSP)", wall=wall, share=t_fmu / wall, measured_share=None,
                         final=x))

    print("| master | wall time | real-time factor | share inside our FMUs (native time / wall) "
          "| share, FMU calls timed |")
    print("|---|---|---|---|---|")
    for r in rows:
        measured = "" if r["measured_share"] is None else f"{100 * r['measured_share']:.0f} % (incl. ctypes)"
        print(f"| {r['master']} | {r['wall'] * 1e3:.1f} ms | {seconds / r['wall']:.0f} | {100 * r['share']:.1f} % "
              f"| {measured} |")
    print("\nfinal plant state per master (alpha1, omega1, alpha2, omega2):")
    for r in rows:
        print(f"  {r['master']}: {r['final']}")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(dict(topology=topo, seconds=seconds, rows=rows), indent=1))
    # Every master ran the same loop: the same final state, or one of them did not.
    ref = np.array(rows[0]["final"])
    for r in rows[1:]:
        x = np.array(list(r["final"].values()) if isinstance(r["final"], dict) else r["final"])
        if np.max(np.abs(x - ref)) > 1e-6:
            sys.exit(f"{r['master']} ends at {x.tolist()}, the native master at {ref.tolist()}: not the same loop")


if __name__ == "__main__":
    main()
