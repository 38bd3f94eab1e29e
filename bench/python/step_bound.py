"""What one fmi2DoStep can cost at worst: every packaged FMI 2.0 co-simulation FMU stepped once
by a step far longer than any experiment (h = 1e6 s), and BouncingBall in the event storm CI
found (g = -2.249e194, h = 4.4 ms). The runtime bounds a step by the integrator's max_steps
(100,000 internal steps for the whole communication step, every stretch between its events
together) and MAX_EVENTS_PER_STEP (100,000 events); this reports the CPU time and the answer of
each call (issue 49). Numbers, not assertions: tests/event_storm.rs asserts the behaviour.

    .venv/bin/python bench/python/step_bound.py [--quick] [--fmus target/fmu]
"""

import argparse
import glob
import os
import shutil
import sys
import time

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

STATUS = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error", 4: "Fatal", 5: "Pending"}


def one_step(path, h, parameters=None):
    """(CPU seconds of the one fmi2DoStep, its status, lastSuccessfulTime, finite?)."""
    md = read_model_description(path)
    if md.coSimulation is None:
        return None
    unzipped = extract(path)
    try:
        fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=unzipped,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="bound",
        )
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        by_name = {v.name: v for v in md.modelVariables}
        for name, value in (parameters or {}).items():
            fmu.setReal([by_name[name].valueReference], [value])
        fmu.exitInitializationMode()
        started = time.process_time()
        try:
            fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=h)
            status = 0
        except Exception as e:  # fmpy raises on anything but fmi2OK
            status = getattr(e, "status", 3)
        seconds = time.process_time() - started
        last = float("nan")
        if status == 2:
            try:
                last = fmu.getRealStatus(2)  # fmi2LastSuccessfulTime
            except Exception:
                pass
        reals = [v.valueReference for v in md.modelVariables if v.type == "Real"]
        values = fmu.getReal(reals) if reals else []
        finite = all(v == v and abs(v) != float("inf") for v in values)
        if status in (0, 1):
            fmu.terminate()
        fmu.freeInstance()
        return seconds, STATUS.get(status, str(status)), last, finite
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fmus", default="target/fmu", help="folder of the packaged FMI 2.0 FMUs")
    ap.add_argument("--quick", action="store_true", help="BouncingBall's storm only (CI: the script still runs)")
    args = ap.parse_args()
    cases = []
    ball = os.path.join(args.fmus, "BouncingBall.fmu")
    if os.path.exists(ball):
        cases.append(("BouncingBall, g = -2.249e194", ball, 0.0044, {"g": -2.249e194}))
    if not args.quick:
        for path in sorted(glob.glob(os.path.join(args.fmus, "*.fmu"))):
            cases.append((os.path.basename(path)[:-4] + ", defaults", path, 1e6, None))
    if not cases:
        sys.exit(f"no FMUs in {args.fmus}: build them first (bash examples/run.sh)")
    print(f"{'case':<40} {'h [s]':>8} {'CPU [s]':>8}  answer   lastSuccessfulTime  values finite")
    worst = 0.0
    for name, path, h, parameters in cases:
        out = one_step(path, h, parameters)
        if out is None:
            continue
        seconds, status, last, finite = out
        worst = max(worst, seconds)
        print(f"{name:<40} {h:>8g} {seconds:>8.3f}  {status:<8} {last:>18.6g}  {finite}")
    print(f"worst CPU time of one fmi2DoStep: {worst:.3f} s")


if __name__ == "__main__":
    main()
