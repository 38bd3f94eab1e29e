"""What the Controller's limit event indicators change for a variable-step integrator (issue 24).

The Controller (PID mode: Kp1 = 8, Ki1 = 1, M_max = 2 N.m) is run in fmpy's Model Exchange with
CVode for 20 s with a constant measured angle alpha1 = 0.1 rad (reference 0): the control error
e1 = -0.1 rad integrates linearly, integral1 = -0.1 t, until the demand M1 = Kp1 e1 + Ki1 integral1
reaches the torque limit at t = (M_max - Kp1 |e1|) / (Ki1 |e1|) = 12 s; there the anti-windup stops
the integral (integral1 = -1.2 from then on): the right-hand side switches. With the event
indicators (M1_margin ... U2_margin) CVode stops at the switch and restarts; without them (the
same FMU with the indicators hidden from fmpy, as an importer saw the FMU before issue 24) it
integrates through the kink. Measure, per relative tolerance: the right-hand sides evaluated
(fmi2GetDerivatives calls), the events, and the largest error of integral1 against the analytic
answer, which is where the kink is.

Usage: python examples/controller_limit_events.py [--fmu target/fmu/Controller.fmu]
"""

import argparse
import copy

import fmpy
import numpy as np

START = {"mode": 2, "M_max": 2.0, "Kp1": 8.0, "Ki1": 1.0, "alpha1": 0.1}
STOP = 20.0
KINK = (2.0 - 8.0 * 0.1) / (1.0 * 0.1)


def analytic(t):
    """integral1 of the run: -0.1 t until the kink, then held."""
    return -0.1 * np.minimum(t, KINK)


def run(fmu, rtol, indicators=True):
    md = fmpy.read_model_description(fmu)
    if not indicators:
        md = copy.deepcopy(md)
        md.numberOfEventIndicators = 0
    calls = {"rhs": 0, "events": 0}

    def logger(message):
        if message.startswith("fmi2GetDerivatives"):
            calls["rhs"] += 1
        elif message.startswith("fmi2EnterEventMode"):
            calls["events"] += 1

    r = fmpy.simulate_fmu(fmu, fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol, stop_time=STOP,
                          output_interval=1e-2, start_values=dict(START), output=["integral1", "M1"],
                          model_description=md, fmi_call_logger=logger)
    return r, calls


def error(r):
    return np.max(np.abs(r["integral1"] - analytic(r["time"])))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--fmu", default="target/fmu/Controller.fmu")
    args = parser.parse_args()
    print(f"Controller, PID, alpha1 = 0.1 rad held, {STOP:g} s: M1 reaches M_max = 2 N.m at t = {KINK:g} s")
    print("rtol     with indicators: rhs  events  max error of integral1   without: rhs  max error")
    for rtol in (1e-4, 1e-6, 1e-8):
        with_r, with_c = run(args.fmu, rtol, True)
        without_r, without_c = run(args.fmu, rtol, False)
        print(f"{rtol:<8.0e} {with_c['rhs']:>20d} {with_c['events']:>7d} {error(with_r):>22.2e}"
              f" {without_c['rhs']:>12d} {error(without_r):>10.2e}")


if __name__ == "__main__":
    main()
