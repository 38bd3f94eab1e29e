"""The paper's linearization (12), open-loop poles and LQR gain (14), from Pendulum.fmu alone.

A (4x4) and B (4x2) of dx/dt = A x + B u at the upright rest position x = 0, u = (M1, M2) = 0
come ONLY from fmi2GetDirectionalDerivative of a model-exchange instance: knowns the four states
(resp. M1, M2), unknowns the four state derivatives. No finite differences, no model equations
here. Then the open-loop poles (eigenvalues of A) and K = lqr(A, B, Q = C'C, R = I), C picking
alpha1 and alpha2, are printed next to the paper's numbers. Exit status 1 if any number is off
(see `problems`).

Usage: python examples/linearize.py [path/to/Pendulum.fmu]   (default target/fmu/Pendulum.fmu)
"""

import argparse
import shutil
import sys

import fmpy
import numpy as np
import scipy.linalg
from fmpy.fmi2 import FMU2Model

# The paper's printed numbers (commas written as points): eq. (12), the poles, eq. (14).
PAPER_A = np.array(
    [[0.0, 1.0, 0.0, 0.0], [44.145, 0.0, -14.715, 0.0], [0.0, 0.0, 0.0, 1.0], [-44.145, 0.0, 29.43, 0.0]]
)
PAPER_B = np.array([[0.0, 0.0], [6.0, -6.0], [0.0, 0.0], [-6.0, 12.0]])
PAPER_POLES = np.array([-7.9571, -3.2031, 3.2031, 7.9571])
PAPER_K = np.array([[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]])
C = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
# "Off": more than 1e-4 relative AND more than half a unit of the paper's 4th printed decimal.
# The second clause is needed because a printed 0.1161 stands for anything in [0.11605, 0.11615]:
# K22 = 0.116086 is 1.2e-4 relative from 0.1161, but it is what the paper rounded.
REL_TOL = 1e-4
PRINTED_HALF_UNIT = 0.5e-4

STATES = ["alpha1", "omega1", "alpha2", "omega2"]
INPUTS = ["M1", "M2"]


def linearize(path):
    """(A, B) of Pendulum.fmu at x = 0, u = 0, from fmi2GetDirectionalDerivative only."""
    md = fmpy.read_model_description(path)
    if md.modelExchange is None or not md.modelExchange.providesDirectionalDerivative:
        raise SystemExit(f"{path}: no model exchange with providesDirectionalDerivative")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    # The derivative of each state, as modelDescription.xml declares it.
    der_of = {d.variable.derivative.name: d.variable.valueReference for d in md.derivatives}
    unknowns = [der_of[s] for s in STATES]
    unzipdir = fmpy.extract(path)
    model = FMU2Model(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.modelExchange.modelIdentifier,
                      instanceName="linearize")
    try:
        model.instantiate()
        model.setupExperiment(startTime=0.0)
        model.enterInitializationMode()
        initial = [f"{n}_0" for n in STATES]  # the initial state is the parameters alpha1_0..omega2_0
        model.setReal([vr[n] for n in initial + INPUTS], [0.0] * 6)  # the upright rest position
        model.exitInitializationMode()
        # No discrete states: one event iteration, then continuous time.
        while model.newDiscreteStates()[0]:
            pass
        model.enterContinuousTimeMode()

        def column(known):
            return model.getDirectionalDerivative(unknowns, [vr[known]], [1.0])

        a = np.column_stack([column(s) for s in STATES])
        b = np.column_stack([column(u) for u in INPUTS])
        model.terminate()
    finally:
        model.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    return a, b


def open_loop_poles(a):
    """Eigenvalues of A, sorted by real part (they are real here: the open loop is a saddle)."""
    eig = np.linalg.eigvals(a)
    return eig[np.argsort(eig.real)]


def lqr_gain(a, b):
    """K = R^-1 B' P with A'P + PA - PBR^-1B'P + Q = 0, Q = C'C, R = I (paper, section 3)."""
    q, r = C.T @ C, np.eye(2)
    p = scipy.linalg.solve_continuous_are(a, b, q, r)
    return np.linalg.solve(r, b.T @ p)


def _off(got, want):
    dev = np.abs(np.asarray(got) - want)
    return (dev > REL_TOL * np.abs(want)) & (dev > PRINTED_HALF_UNIT)


def problems(a, b, poles, k):
    """The numbers that are off from the paper's, as text; empty when all agree."""
    found = []
    for name, got, want in [("A", a, PAPER_A), ("B", b, PAPER_B), ("pole", poles, PAPER_POLES), ("K", k, PAPER_K)]:
        got = np.real_if_close(got)
        if np.iscomplexobj(got):
            found.append(f"{name}: complex values {got}")
            continue
        for idx in zip(*np.nonzero(_off(got, want))):
            found.append(f"{name}{''.join(str(i + 1) for i in idx)} = {got[idx]:.6g}, paper {want[idx]:.6g}")
    return found


def _rows(label, got, want):
    print(f"{label}  (from the FMU  |  paper)")
    for g, w in zip(np.atleast_2d(got), np.atleast_2d(want)):
        print("  " + " ".join(f"{v:11.6f}" for v in g) + "   | " + " ".join(f"{v:9.4f}" for v in w))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", nargs="?", default="target/fmu/Pendulum.fmu", help="Pendulum.fmu (default %(default)s)")
    args = parser.parse_args(argv)
    a, b = linearize(args.fmu)
    poles = open_loop_poles(a)
    k = lqr_gain(a, b)
    print(f"Linearization of {args.fmu} at the upright rest position, by fmi2GetDirectionalDerivative\n")
    _rows("A, eq. (12)", a, PAPER_A)
    _rows("B, eq. (12)", b, PAPER_B)
    _rows("open-loop poles", np.real_if_close(poles), PAPER_POLES)
    _rows("K = lqr(A, B, C'C, I), eq. (14)", k, PAPER_K)
    closed = np.linalg.eigvals(a - b @ k)
    print("closed-loop poles eig(A - BK): " + ", ".join(f"{p:.5f}" for p in closed[np.argsort(closed.real)]))
    found = problems(a, b, poles, k)
    for p in found:
        print("OFF: " + p)
    rel_k = np.abs(k - PAPER_K).max()
    if found:
        print(f"FAILED: {len(found)} number(s) differ from the paper's by more than {REL_TOL:g} relative "
              "and more than its rounding")
        return 1
    print(f"OK: A, B match eq. (12); poles ±{poles[-1].real:.4f}, ±{poles[-2].real:.4f}; "
          f"K matches eq. (14) to its printed digits (max |K - K_paper| = {rel_k:.1e})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
