#!/usr/bin/env python3
"""Independent importers over every FMU the main job makes (issue 49, item 4).

Runs the importers in ../shared/independent/bin (nobody here wrote them) on every FMU in
target/fmu/*.fmu (FMI 2.0), target/fmu/fmi3/*.fmu (FMI 3.0) and target/fmu/containers/**.fmu:

- `fmusim-rs validate` (its `error:` / `warning:` lines count: it may exit 0 on schema errors);
- fmuCheck (FMI 2.0 only) for each interface at its default (h = span/500) and at
  h = 0.01, 0.02, 0.03, 0.05, 0.1, 1/3 (its time is t += h), with -n 0 (a row per step);
- the C fmusim (ME with its Euler, CS) and fmusim-rs `simulate` (ME with its Euler, CS; FMI 3.0 CS
  also with --event-mode-used, and with --event-mode-used --early-return-allowed) at the default
  experiment;
- each result against our own fmpy run of the same FMU (tolerances below), and side by side with
  the C Reference-FMUs for the models re-made in reference-fmus/.

Any warning, error, crash, timeout or disagreement beyond tolerance fails. Prints one line per
tool and FMU, then `independent importers: N passed, N failed`; exits 1 on any failure.
Run it from anywhere with the venv's python: `.venv/bin/python tests/independent/run.py [FMU...]`
(without FMUs: every FMU of target/fmu/). tests/independent/README.md says what each number means.
"""

import argparse
import csv
import glob
import json
import math
import os
import pickle
import re
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# As tests refer to it: beside the project (CI clones the repository elsewhere, shared/ beside it).
IND = Path("../shared/independent")
BIN = IND / "bin"
REFERENCE_FMUS = IND / "reference-fmus"
# The models re-made in reference-fmus/, packaged with the Reference-FMUs' identifiers.
REMADE = {"BouncingBall", "Dahlquist", "Feedthrough", "Stair", "VanDerPol", "StateSpace", "Clocks"}

TIMEOUT = 60  # seconds per tool run
WORKERS = 2  # the machine has 2 cores
FMUCHECK_STEPS = [0.01, 0.02, 0.03, 0.05, 0.1, 1 / 3]

# Tolerances, as max |a - b| / (largest |b| of that variable over the run), per comparison.
TOL_CS = 1e-6  # CS against fmpy CS of the same FMU on the same grid: the FMU's own integrator
TOL_EULER = 1e-8  # ME with the tool's fixed-step Euler against fmpy's Euler with the same step
TOL_SAME_TOOL = 1e-9  # side by side ME: ours and the Reference's in the same tool, solver, step
# Side by side CS: ours against a tight reference (fmpy CVode, rtol 1e-10). Our integrator's
# default relative tolerance is 1e-6 per step (docs/writing-an-fmu.md); over VanDerPol's 20 s the
# global error reaches 6e-6 at h = 0.1.
TOL_TIGHT_OURS = 1e-5
TOL_EVENT_TIME = 1e-6  # an Event Mode time (early return) against the tight run's event, in s
TIME_EPS = 1e-9  # two output times are the same time within TIME_EPS * max(1, |t|)
TIGHT_RTOL = 1e-10


def say(*a):
    print(*a, flush=True)


# ---------------------------------------------------------------------------------------------
# What an FMU is: read from its modelDescription.xml by fmpy.


def describe(path):
    import fmpy

    md = fmpy.read_model_description(str(path), validate=False)
    de = md.defaultExperiment
    start = float(de.startTime) if de is not None and de.startTime is not None else 0.0
    stop = float(de.stopTime) if de is not None and de.stopTime is not None else 1.0
    step = float(de.stepSize) if de is not None and de.stepSize is not None else (stop - start) / 500
    kinds = {}
    for v in md.modelVariables:
        if v.causality != "output":
            continue
        if v.type in ("Real", "Float64", "Float32"):
            kinds[v.name] = "continuous" if v.variability == "continuous" else "discrete real"
        elif v.type in ("String", "Binary", "Clock"):
            continue
        else:
            kinds[v.name] = "discrete"
    clocks = any(v.type == "Clock" for v in md.modelVariables)
    ident = (md.coSimulation or md.modelExchange or md.scheduledExecution).modelIdentifier
    return {
        "version": md.fmiVersion[0],  # "2" or "3"
        "me": md.modelExchange is not None,
        "cs": md.coSimulation is not None,
        "event_mode": bool(md.coSimulation is not None and getattr(md.coSimulation, "hasEventMode", False)),
        "start": start,
        "stop": stop,
        "step": step,
        "kinds": kinds,
        "clocks": clocks,
        "ident": ident,
    }


# ---------------------------------------------------------------------------------------------
# fmpy references, computed in a child process per FMU (a crash or hang there is a timeout here).


def fmpy_refs(fmu, specs_path, out_path):
    import fmpy
    import numpy as np

    specs = json.loads(Path(specs_path).read_text())
    out = {}
    for s in specs:
        kw = dict(start_time=s["start"], stop_time=s["stop"], output_interval=s["h"], timeout=TIMEOUT)
        try:
            if s["kind"] == "cs":
                r = fmpy.simulate_fmu(fmu, fmi_type="CoSimulation", **kw)
            elif s["kind"] == "euler":
                r = fmpy.simulate_fmu(fmu, fmi_type="ModelExchange", solver="Euler", step_size=s["h"], **kw)
            else:  # tight: ME with CVode at TIGHT_RTOL, else CS on a fine grid
                if s["me"]:
                    r = fmpy.simulate_fmu(fmu, fmi_type="ModelExchange", relative_tolerance=TIGHT_RTOL, **kw)
                else:
                    r = fmpy.simulate_fmu(fmu, fmi_type="CoSimulation", **kw)
            cols = {"time": np.asarray(r["time"], dtype=float)}
            for n in r.dtype.names:
                if n == "time" or r[n].dtype.kind not in "biuf":
                    continue
                v = np.asarray(r[n], dtype=float)
                if v.ndim == 1:
                    cols[n] = v
                else:  # an array variable: one column per element, as read_csv names them
                    v = v.reshape(len(v), -1)
                    for k in range(v.shape[1]):
                        cols[f"{n}[{k + 1}]"] = v[:, k]
            out[s["name"]] = cols
        except Exception as e:  # noqa: BLE001 - reported as a failed reference
            out[s["name"]] = {"error": f"{type(e).__name__}: {e}"}
    Path(out_path).write_bytes(pickle.dumps(out))


# ---------------------------------------------------------------------------------------------
# Results: CSV files of the tools, as columns of floats (strings dropped).


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return None
    names = [n.strip() for n in rows[0]]
    cols = {}
    for row in rows[1:]:
        if len(row) != len(names):
            continue
        for n, x in zip(names, row):
            # An array variable's elements are one cell, separated by spaces: y[1], y[2], ...
            xs = x.split()
            for k, x in enumerate(xs or [""]):
                name = n if len(xs) <= 1 else f"{n}[{k + 1}]"
                if x in ("true", "false"):
                    v = 1.0 if x == "true" else 0.0
                else:
                    try:
                        v = float(x)
                    except ValueError:
                        v = None
                cols.setdefault(name, []).append(v)
    out = {}
    for n, v in cols.items():
        if all(x is not None for x in v):
            out[n] = v
    out["time"] = cols.get("time", [])
    return out if all(len(v) == len(out["time"]) for v in out.values()) else None


def right_limits(res):
    """Keep the last row of each time (the value after the event at an event instant)."""
    t = res["time"]
    keep = [i for i in range(len(t)) if i + 1 == len(t) or t[i + 1] != t[i]]
    return {n: [v[i] for i in keep] for n, v in res.items()}


def same_time(a, b):
    return abs(a - b) <= TIME_EPS * max(1.0, abs(a), abs(b))


def kind_of(kinds, name):
    """The kind of an output or of an element y[k] of an array output y."""
    return kinds.get(name) or kinds.get(name.split("[")[0])


def event_times(tight, kinds, stop):
    """Event windows [a, b] from the tight reference: a time listed twice (fmpy ME records both
    limits), or two successive rows between which a discrete output changes."""
    t = list(tight["time"])
    wins = []
    for i in range(len(t) - 1):
        if t[i + 1] == t[i]:
            wins.append((t[i], t[i]))
        elif any(
            kind_of(kinds, n) not in (None, "continuous") and tight[n][i + 1] != tight[n][i]
            for n in tight
            if n != "time"
        ):
            wins.append((t[i], t[i + 1]))
    if t and not same_time(t[-1], stop):  # the FMU ended the run (terminateSimulation) at t[-1]
        wins.append((t[-1], t[-1]))
    return wins


def near_event(t, wins):
    eps = TIME_EPS * max(1.0, abs(t))
    return any(a - eps <= t <= b + eps for a, b in wins)


def compare(res, ref, kinds, tol, wins=(), discrete=True, continuous=True):
    """Compares res with ref on their shared output times (right limits). Continuous outputs within
    tol of the variable's largest magnitude; Integer/Boolean/Enumeration exactly and discrete Reals
    within tol, both away from events (not within TIME_EPS of an event window of the tight
    reference: at an event instant one result may hold the left limit, the other the right).
    Returns (number of points compared, list of disagreements)."""
    a, b = right_limits(res), right_limits(ref)
    ta, tb = a["time"], b["time"]
    names = [n for n in a if n != "time" and n in b and kind_of(kinds, n)]
    if not names or not ta:
        return 0, ["no shared outputs to compare"]
    scale = {n: max((abs(x) for x in b[n] if math.isfinite(x)), default=0.0) or 1.0 for n in names}
    bad = []
    worst = {}
    j = 0
    shared = 0
    for i, t in enumerate(ta):
        while j < len(tb) and tb[j] < t and not same_time(tb[j], t):
            j += 1
        if j == len(tb):
            break
        # The nearest: t += h puts 4.99999999999998 and 5.0 (an event's two rows) within TIME_EPS.
        while j + 1 < len(tb) and abs(tb[j + 1] - t) < abs(tb[j] - t):
            j += 1
        if not same_time(tb[j], t):
            continue
        shared += 1
        at_event = near_event(t, wins)
        for n in names:
            x, y = a[n][i], b[n][j]
            kind = kind_of(kinds, n)
            if kind == "discrete":
                if discrete and x != y and not at_event:
                    bad.append(f"{n} = {x:g} at t = {t!r}, reference {y:g}")
            elif continuous if kind == "continuous" else discrete:
                if math.isfinite(x) and math.isfinite(y):
                    e = abs(x - y) / scale[n]
                else:  # both diverged alike (an explicit Euler at a large step), or one did
                    e = 0.0 if (x == y or (math.isnan(x) and math.isnan(y))) else math.inf
                if e > tol and (kind == "continuous" or not at_event):
                    if e > worst.get(n, (0,))[0]:
                        worst[n] = (e, t, float(x), float(y))
    for n, (e, t, x, y) in worst.items():
        bad.append(f"{n}: error {e:.2e} > {tol:g} (worst at t = {t:.9g}: {x!r}, reference {y!r})")
    if shared == 0:
        bad.append("no shared output times")
    return shared, bad[:4] + ([f"... {len(bad) - 4} more"] if len(bad) > 4 else [])


def event_rows(res):
    t = res["time"]
    return [t[i] for i in range(len(t) - 1) if t[i + 1] == t[i]]


def check_event_mode(res, wins, start, h, early_return, tol):
    """fmusim-rs --event-mode-used records two rows (both limits) at each time the FMU asked for Event
    Mode. With early return each event of the tight run is such a time (within tol); without it,
    the end of every communication step that holds such an event. No other such rows. An event of
    a CS-only FMU's tight run is known to lie between two of its rows: any time between counts."""
    got = event_rows(res)
    stop = res["time"][-1] if res["time"] else start
    # Not the instant the run ended at (the FMU's terminateSimulation): no Event Mode after it.
    ev = [(a, b) for a, b in wins if a > start and b < stop and not same_time(b, stop)]
    if not early_return:  # the end of the step that holds it

        def end(t):
            return start + math.ceil((t - start) / h - 1e-9) * h

        ev = [(end(a), end(b)) for a, b in ev]
    want = sorted(set(ev))
    missing = [w for w in want if not any(w[0] - tol <= g <= w[1] + tol for g in got)]
    extra = [g for g in got if not any(w[0] - tol <= g <= w[1] + tol for w in want)]
    bad = []
    if missing:
        bad.append(f"no Event Mode at {len(missing)} of {len(want)} expected times (first {missing[0][0]:.9g})")
    if extra:
        bad.append(f"Event Mode at {len(extra)} unexpected times (first {extra[0]:.9g})")
    return bad


# ---------------------------------------------------------------------------------------------
# Tool runs.


def run_cmd(cmd, timeout=TIMEOUT):
    started = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, errors="replace")
        return p.returncode, p.stdout + p.stderr, time.monotonic() - started
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"") + (e.stderr or b"")
        if isinstance(out, bytes):
            out = out.decode(errors="replace")
        return "timeout", out, time.monotonic() - started


STATUS_RE = re.compile(r"-> (?:fmi[23])?(Warning|Discard|Error|Fatal|Pending)\b")
C_LOG_RE = re.compile(r"^\[(Warning|Discard|Error|Fatal)\] ")


def problems_in_log(tool, out):
    """Warnings and errors in a simulator's output: FMI calls that returned other than OK
    (--log-fmi-calls) and messages the FMU logged with such a status (--logging-on)."""
    found = []
    lines = out.splitlines()
    steps = [i for i, l in enumerate(lines) if re.search(r"fmi[23]DoStep\(", l)]
    # FMI 2.0 co-simulation ends a run the FMU stops (terminateSimulation) with fmi2Discard from the
    # last fmi2DoStep (fmi2Terminated = true): that status, and a Discard message the FMU logged
    # in that call, are how the standard says it, not a warning.
    ended = bool(steps) and "fmi2DoStep(" in lines[steps[-1]] and re.search(r"-> (fmi2)?Discard$", lines[steps[-1]].strip())
    last_call = range(steps[-2] + 1 if len(steps) > 1 else 0, steps[-1] + 1) if ended else range(0)
    for i, line in enumerate(lines):
        s = line.strip()
        if i in last_call and re.search(r"discard", s, re.I) and not re.search(r"warning|error|fatal", s, re.I):
            continue
        if STATUS_RE.search(s) or C_LOG_RE.match(s):
            found.append(s)
        elif tool == "fmusim-rs" and not s.startswith("[FMI]") and re.search(
            r"\b(warning|error|discard|fatal|panick?ed)\b", s, re.I
        ):
            found.append(s)
        elif tool == "fmusim" and not re.match(r"^fmi[23]\w+\(", s) and re.search(
            r"\b(warning|error|failed|fatal)\b", s, re.I
        ):
            found.append(s)
    return found


def parse_fmucheck(out):
    if re.search(r"does not support|not supported", out):
        return None
    chk = re.search(r"Checker reported:\s*(\d+) Warning\(s\)\s*(\d+) Error\(s\)", out)
    fmu = re.search(r"FMU reported:\s*(\d+) warning\(s\) and error\(s\)", out)
    end = re.search(r"(?:Simulation finished successfully|FMU requests to terminate simulation) at time ([-+0-9.eE]+)", out)
    n_fmu = int(fmu.group(1)) if fmu else None
    # The FMU ended the run (FMI 2.0: fmi2Discard from its last fmi2DoStep, fmi2Terminated): a
    # Discard message it logged in that last call is the standard's way to say so, not a warning.
    msgs = re.findall(r"\[FMU\]\[logStatus(\w+)\]", out)
    if n_fmu and "FMU requests to terminate simulation" in out and msgs and msgs[-1] == "Discard":
        n_fmu -= 1
    return {
        "checker": (int(chk.group(1)) + int(chk.group(2))) if chk else None,
        "fmu": n_fmu,
        "end": float(end.group(1)) if end else None,
        "lines": [l.strip() for l in out.splitlines() if re.search(r"\[(WARNING|ERROR|FATAL)\]", l)][:3],
    }


# ---------------------------------------------------------------------------------------------


class Tally:
    def __init__(self):
        self.rows = {}  # (tool, fmu) -> [passed, warnings, failed, [messages], [skips]]

    def get(self, tool, fmu):
        return self.rows.setdefault((tool, fmu), [0, 0, 0, [], []])

    def ok(self, tool, fmu):
        self.get(tool, fmu)[0] += 1

    def fail(self, tool, fmu, what, warnings=0):
        r = self.get(tool, fmu)
        r[1] += warnings
        r[2] += 1
        r[3].append(what)

    def skip(self, tool, fmu, why):
        self.get(tool, fmu)[4].append(why)


def fmt_h(h):
    return "1/3" if abs(h - 1 / 3) < 1e-15 else f"{h:g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("fmus", nargs="*", help="FMU files (default: every FMU the main job makes)")
    ap.add_argument("--records", help="write 'name<TAB>passed<TAB>failed' per tool and FMU (tests/run.sh)")
    ap.add_argument("--keep", help="keep the results in this folder")
    ap.add_argument("--dir", default="target/fmu", help="where the FMUs are (default: target/fmu)")
    ap.add_argument("--fmpy-refs", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.fmpy_refs:
        fmpy_refs(*args.fmpy_refs)
        return 0
    given = [Path(f).resolve() for f in args.fmus]
    top = Path(args.dir).resolve()
    os.chdir(ROOT)
    started = time.monotonic()
    if given:
        fmus = [Path(os.path.relpath(f, ROOT)) for f in given]
    else:
        fmus = [Path(f) for f in sorted(glob.glob(f"{top}/*.fmu")) + sorted(glob.glob(f"{top}/fmi3/*.fmu"))]
        fmus += [Path(f) for f in sorted(glob.glob(f"{top}/containers/**/*.fmu", recursive=True))]
    if not fmus:
        say("independent importers: no FMU in target/fmu/ (run the main job first)")
        say("independent importers: 0 passed, 1 failed")
        return 1
    for tool in ("fmusim", "fmusim-rs", "fmuCheck"):
        if not os.access(BIN / tool, os.X_OK):
            say(f"independent importers: {BIN / tool} is missing (../shared/independent/README.md)")
            say("independent importers: 0 passed, 1 failed")
            return 1
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="independent-"))
    work.mkdir(parents=True, exist_ok=True)
    tally = Tally()
    jobs = []  # (key, cmd, timeout)
    plans = {}  # fmu label -> what to compare after the runs

    def label_of(p):
        """target/fmu/fmi3/Stair.fmu -> fmi3/Stair.fmu"""
        p = Path(p).resolve()
        return str(p.relative_to(top)) if p.is_relative_to(top) else os.path.relpath(p, ROOT)

    def add_runs(fmu, info, label, side):
        """Queues the tool runs of one FMU; side: the label of our FMU this Reference FMU stands beside."""
        d = work / re.sub(r"[^A-Za-z0-9_.-]", "_", label).lstrip("._")
        d.mkdir(parents=True, exist_ok=True)
        runs = []
        base = ["--start-time", repr(info["start"]), "--stop-time", repr(info["stop"]), "--output-interval", repr(info["step"])]
        if not side:
            jobs.append(((label, "validate"), [str(BIN / "fmusim-rs"), "validate", str(fmu)], TIMEOUT))
        clocked = info["clocks"]
        for itf in ("me", "cs"):
            if not info[itf]:
                continue
            if info["version"] == "2":
                hs = [None] + FMUCHECK_STEPS
                for h in hs:
                    name = f"fmuCheck -k {itf}" + (f" -h {fmt_h(h)}" if h else "")
                    csvp = d / f"fmucheck-{itf}-{fmt_h(h) if h else 'default'}.csv".replace("/", "_")
                    cmd = [str(BIN / "fmuCheck"), "-k", itf, "-n", "0" if h else "500", "-s", repr(info["stop"]), "-o", str(csvp)]
                    if h:
                        cmd += ["-h", repr(h)]
                    cmd.append(str(fmu))
                    hh = h if h else (info["stop"] - info["start"]) / 500
                    runs.append(dict(tool="fmuCheck", name=name, csv=csvp, itf=itf, h=hh))
                    jobs.append(((label, name), cmd, TIMEOUT))
            if clocked:
                continue
            # The C fmusim: ME with its Euler (fixed step = output interval), CS.
            csvp = d / f"fmusim-{itf}.csv"
            cmd = [str(BIN / "fmusim"), "--interface-type", itf, "--logging-on", "--log-fmi-calls", *base, "--output-file", str(csvp)]
            if itf == "me":
                cmd += ["--solver", "euler"]
            name = f"fmusim {itf}" + (" euler" if itf == "me" else "")
            runs.append(dict(tool="fmusim", name=name, csv=csvp, itf=itf, h=info["step"]))
            jobs.append(((label, name), cmd + [str(fmu)], TIMEOUT))
            # fmusim-rs: ME with its Euler, CS; FMI 3.0 CS also with event mode, with and without early return.
            variants = [[]]
            if itf == "cs" and info["version"] == "3" and info["event_mode"]:
                variants += [["--event-mode-used"], ["--event-mode-used", "--early-return-allowed"]]
            elif itf == "cs" and info["version"] == "3" and not side:
                tally.skip("fmusim-rs", label, "no --event-mode-used: the FMU declares no hasEventMode")
            for v in variants:
                tag = "-".join(x.strip("-") for x in v) or "plain"
                csvp = d / f"fmusim-rs-{itf}-{tag}.csv"
                cmd = [str(BIN / "fmusim-rs"), "simulate", "--interface-type", itf, "--logging-on", "--log-fmi-calls", *base, "--output-file", str(csvp), *v]
                if itf == "me":
                    cmd += ["--solver", "euler", "--fixed-step-size", repr(info["step"])]
                name = f"fmusim-rs {itf}" + (" euler" if itf == "me" else "") + "".join(" " + x for x in v)
                runs.append(dict(tool="fmusim-rs", name=name, csv=csvp, itf=itf, h=info["step"], opts=v))
                jobs.append(((label, name), cmd + [str(fmu)], TIMEOUT))
        # fmpy references of this FMU: CS on each grid, Euler on each ME grid, one tight run.
        specs = []
        seen = set()
        for r in runs:
            kind = "cs" if r["itf"] == "cs" else "euler"
            key = f"{kind}@{r['h']!r}"
            r["ref"] = key
            if key not in seen:
                seen.add(key)
                specs.append(dict(name=key, kind=kind, h=r["h"], start=info["start"], stop=info["stop"], me=info["me"]))
        if runs:
            specs.append(dict(name="tight", kind="tight", h=info["step"] / 10, start=info["start"], stop=info["stop"], me=info["me"]))
            sp = d / "fmpy-specs.json"
            sp.write_text(json.dumps(specs))
            jobs.append(((label, "fmpy"), [sys.executable, __file__, "--fmpy-refs", str(fmu.resolve()), str(sp), str(d / "fmpy.pkl")], TIMEOUT + 20 * len(specs)))
        return dict(fmu=fmu, info=info, runs=runs, refs=d / "fmpy.pkl", side=side)

    for fmu in fmus:
        label = label_of(fmu)
        try:
            info = describe(fmu)
        except Exception as e:  # noqa: BLE001
            tally.fail("fmpy", label, f"cannot read modelDescription.xml: {e}")
            continue
        plans[label] = add_runs(fmu, info, label, None)
        if info["version"] == "2":
            pass
        else:
            tally.skip("fmuCheck", label, "fmuCheck imports FMI 1.0 and 2.0 only")
        if info["clocks"]:
            why = "reads clocked variables outside Event Mode and drives no clocks (FMI 3.0 forbids the first; ours refuse it)"
            tally.skip("fmusim", label, "the C fmusim " + why)
            tally.skip("fmusim-rs", label, "fmusim-rs " + why)
        ref = REFERENCE_FMUS / f"{info['version']}.0" / f"{info['ident']}.fmu"
        if info["ident"] in REMADE and ref.exists() and ref.resolve() != fmu.resolve():
            rlabel = f"Reference {info['version']}.0/{info['ident']}"
            if rlabel not in plans:
                # Their runs on our experiment: the same grid in every tool.
                rinfo = {**describe(ref), **{k: info[k] for k in ("start", "stop", "step")}}
                plans[rlabel] = add_runs(ref, rinfo, rlabel, label)
            plans[label]["beside"] = rlabel

    say(f"independent importers: {len(fmus)} FMUs, {len(jobs)} runs, {WORKERS} at a time, timeout {TIMEOUT} s each; results in {work}")
    results = {}

    def do(job):
        key, cmd, to = job
        results[key] = run_cmd(cmd, to)

    # Longest first: the fmpy references, then the rest in order.
    jobs.sort(key=lambda j: 0 if j[0][1] == "fmpy" else 1)
    with ThreadPoolExecutor(WORKERS) as ex:
        list(ex.map(do, jobs))
    ran = time.monotonic() - started
    per_tool = {}
    for (_, name), (_, _, secs) in results.items():
        k = name.split(" ")[0] if name not in ("validate", "fmpy") else name
        per_tool[k] = per_tool.get(k, 0) + secs

    # -----------------------------------------------------------------------------------------
    # Judge.
    loaded = {}

    def refs_of(label):
        if label not in loaded:
            rc, out, _ = results.get((label, "fmpy"), (None, "", 0))
            p = plans[label]["refs"]
            if rc == 0 and p.exists():
                loaded[label] = pickle.loads(p.read_bytes())
            else:
                loaded[label] = {"_error": f"fmpy references: exit {rc}: {out.strip()[-300:]}"}
        return loaded[label]

    def tool_of(name):
        return name.split(" ")[0]

    side_info = []  # lines printed for the Reference FMUs (their own deviations: not ours to fail)
    for label, plan in plans.items():
        info = plan["info"]
        kinds = info["kinds"]
        mine = plan["side"] is None
        if mine:
            rc, out, _ = results[(label, "validate")]
            msgs = [l.strip() for l in out.splitlines() if re.match(r"\s*(error|warning)\b", l.strip(), re.I)]
            if rc != 0 or msgs:
                tally.fail("fmusim-rs validate", label, f"exit {rc}: " + "; ".join(msgs[:3]), warnings=len(msgs))
            else:
                tally.ok("fmusim-rs validate", label)
        refs = refs_of(label) if plan["runs"] else {}
        if "_error" in refs:
            if mine:
                tally.fail("fmpy", label, refs["_error"])
            else:
                side_info.append(f"{label}: {refs['_error']}")
            continue
        tight = refs.get("tight", {})
        wins = event_times(tight, kinds, info["stop"]) if "time" in tight else []
        for r in plan["runs"]:
            tool = tool_of(r["name"])
            rc, out, secs = results[(label, r["name"])]
            r["secs"] = secs
            problems = []
            warnings = 0
            if tool == "fmuCheck":
                fc = parse_fmucheck(out)
                if fc is None:
                    tally.skip(tool, label, f"{r['name']}: the FMU does not have this interface")
                    r["skip"] = True
                    continue
                if fc["checker"] is None or fc["fmu"] is None:
                    problems.append(f"no summary in its output (exit {rc})")
                else:
                    warnings = fc["checker"] + fc["fmu"]
                    if warnings:
                        problems.append(f"checker {fc['checker']}, FMU-reported {fc['fmu']} warning(s)/error(s): " + " | ".join(fc["lines"]))
                if fc["end"] is None:
                    problems.append("did not finish the simulation")
                r["end"] = fc["end"]
            elif tool == "fmusim-rs" and r["itf"] == "me" and "is too close to current time" in out:
                # fmusim-rs 0.8.0's Euler gives up when a state event leaves it within round-off
                # of the next output point (the Reference-FMUs' BouncingBall stops the same way).
                tally.skip(tool, label, f"{r['name']}: fmusim-rs stops with its own 'Next time is too close to current time' after a state event")
                r["skip"] = True
                continue
            else:
                found = problems_in_log(tool, out)
                warnings = len(found)
                if found:
                    problems.append(f"{len(found)} warning(s)/error(s): " + " | ".join(found[:2]))
            if rc == "timeout":
                problems.append(f"timeout after {TIMEOUT} s")
            elif rc != 0:
                problems.append(f"exit status {rc}: " + " | ".join(out.strip().splitlines()[-2:]))
            res = read_csv(r["csv"]) if Path(r["csv"]).exists() else None
            r["res"] = res
            if not res or not res.get("time"):
                problems.append("no result file")
            else:
                ref = refs.get(r["ref"], {})
                diverged = "discard" in ref.get("error", "").lower() or (
                    "error" not in ref and any(not math.isfinite(x) for v in ref.values() for x in v)
                )
                if r["itf"] == "me" and diverged:
                    # Forward Euler at this step is unstable for the model (VanDerPol at h = 1/3):
                    # the states overflow and our FMU answers Discard. Nothing to compare.
                    tally.skip(tool, label, f"{r['name']}: forward Euler at h = {fmt_h(r['h'])} diverges on this model (fmpy's Euler of the same step: {ref.get('error', 'non-finite values')[:80]})")
                    r["skip"] = True
                    continue
                if "error" in ref or "time" not in ref:
                    problems.append(f"fmpy {r['ref']}: {ref.get('error', 'missing')}")
                else:
                    if r["itf"] == "cs":
                        n, bad = compare(res, ref, kinds, TOL_CS, wins)
                    elif tool == "fmuCheck":
                        # fmuCheck's Euler keeps t += h and handles a state event its own way:
                        # continuous outputs against fmpy's Euler of the same step up to the
                        # first event, discrete outputs against the tight run away from events.
                        first = min((a for a, _ in wins), default=math.inf)
                        until = {k: v[: sum(1 for t in res["time"] if t < first)] for k, v in res.items()}
                        n, bad = compare(until, ref, kinds, TOL_EULER, wins, discrete=False)
                        if "time" in tight:
                            bad += compare(res, tight, kinds, 0, wins, continuous=False)[1]
                    else:
                        n, bad = compare(res, ref, kinds, TOL_EULER, wins)
                    problems += [f"against fmpy {r['ref']}: {b}" for b in bad]
                    if tool == "fmuCheck" and r.get("end") is not None:
                        tend = ref["time"][-1]
                        if abs(r["end"] - tend) > r["h"] * 1.000001:
                            problems.append(f"ended at t = {r['end']!r}, fmpy at {tend!r}")
                if r.get("opts") and "time" in tight:
                    problems += check_event_mode(res, wins, info["start"], r["h"], "--early-return-allowed" in r["opts"], TOL_EVENT_TIME)
            if mine:
                if problems:
                    tally.fail(tool, label, f"{r['name']}: " + "; ".join(problems), warnings)
                else:
                    tally.ok(tool, label)
            else:
                r["problems"] = problems

    # Side by side with the C Reference-FMUs.
    for label, plan in plans.items():
        rl = plan.get("beside")
        if not rl:
            continue
        theirs = {r["name"]: r for r in plans[rl]["runs"]}
        kinds = {n: k for n, k in plan["info"]["kinds"].items() if n in plans[rl]["info"]["kinds"]}
        rrefs = refs_of(rl)
        tight = rrefs.get("tight", {})
        wins = event_times(tight, kinds, plans[rl]["info"]["stop"]) if "time" in tight else []
        tool = "beside Reference"
        for r in plan["runs"]:
            t = theirs.get(r["name"])
            if r.get("skip") or not t or t.get("skip"):
                continue
            if t.get("problems"):
                side_info.append(f"{rl} {t['name']}: {t['problems'][0]}")
            if not r.get("res") or not t.get("res"):
                tally.fail(tool, label, f"{r['name']}: no result to compare")
                continue
            bad = []
            if r["itf"] == "me":
                a, b = r["res"], t["res"]
                if len(a["time"]) != len(b["time"]) or any(not same_time(x, y) for x, y in zip(a["time"], b["time"])):
                    bad.append(f"other output rows: {len(a['time'])} against the Reference's {len(b['time'])}")
                else:
                    bad += compare(a, b, kinds, TOL_SAME_TOOL)[1]
            elif "time" not in tight:
                bad.append("no tight reference of the Reference FMU")
            else:
                bad += [f"against tight: {x}" for x in compare(r["res"], tight, kinds, TOL_TIGHT_OURS, wins)[1]]
                _, their = compare(t["res"], tight, kinds, TOL_TIGHT_OURS, wins)
                if their:
                    side_info.append(f"{rl} {t['name']} (their CS is fixed-step Euler) against tight: {their[0]}")
            if bad:
                tally.fail(tool, label, f"{r['name']}: " + "; ".join(bad))
            else:
                tally.ok(tool, label)

    # -----------------------------------------------------------------------------------------
    order = ["fmusim-rs validate", "fmuCheck", "fmusim", "fmusim-rs", "beside Reference", "fmpy"]
    total_p = total_f = 0
    records = []
    for (tool, label), (p, w, f, msgs, skips) in sorted(tally.rows.items(), key=lambda kv: (kv[0][1], order.index(kv[0][0]))):
        if p or f:
            say(f"{tool} {label}: {p} passed, {w} warnings, {f} failed")
            records.append((f"{tool} {label}", p, f))
        for m in msgs:
            say(f"    FAIL {m}")
        for s in dict.fromkeys(skips) if plans.get(label, {}).get("side") is None else ():
            say(f"{tool} {label}: skipped: {s}")
        total_p += p
        total_f += f
    for s in side_info:
        say(f"  (theirs, not counted) {s}")
    say("seconds per tool (summed over runs): " + ", ".join(f"{k} {v:.0f}" for k, v in sorted(per_tool.items())))
    say(f"runs: {ran:.0f} s; judged in {time.monotonic() - started - ran:.0f} s; results in {work}")
    if args.records:
        Path(args.records).write_text("".join(f"{n}\t{p}\t{f}\n" for n, p, f in records))
    if not args.keep and not total_f:
        shutil.rmtree(work, ignore_errors=True)  # kept when something failed, to read
    say(f"independent importers: {total_p} passed, {total_f} failed")
    return 1 if total_f else 0


if __name__ == "__main__":
    sys.exit(main())
