"""The closed loop as one FMU: target/fmu/containers/PendulumLQR.fmu (written by
`cargo fmu container target/fmu/PendulumLQR.ssp`: the Pendulum and the Controller inside, the
native runner's master in its binary) simulated by fmpy's simulate_fmu like any other FMU, against
the native runner (the rustfmu_runner module) on the SSP file it was made from, at the same step.

fmpy's steps are (k+1) h - k h, a few ulps off h, so the two differ in the last bits (the
container driven with the runner's own steps gives 0: tests/python/test_container.py). Prints
the largest difference of every output and writes both runs to container_demo.csv. The FMI 3.0
container of the same system (containers/fmi3/, the same binary behind FMI 3.0's API) runs the
same way and is compared too.

Usage: python examples/container_demo.py [--out DIR] [--fmu-dir target/fmu] [--stop 5] [--system PendulumLQR]
"""

import argparse
import csv
import pathlib

import fmpy
import numpy as np

import rustfmu_runner


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out")
    parser.add_argument("--fmu-dir", default="target/fmu")
    parser.add_argument("--stop", type=float, default=5.0)
    parser.add_argument("--system", default="PendulumLQR")
    args = parser.parse_args()
    fmus = pathlib.Path(args.fmu_dir)
    container = fmus / "containers" / f"{args.system}.fmu"
    md = fmpy.read_model_description(str(container))
    h = float(md.defaultExperiment.stepSize)
    record = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    one = fmpy.simulate_fmu(str(container), stop_time=args.stop, step_size=h, output_interval=h, output=record)
    native = rustfmu_runner.System(str(fmus / f"{args.system}.ssp")).run(args.stop, h, record=record)
    worst = max(float(np.max(np.abs(np.asarray(one[r], float) - np.asarray(native[r], float)))) for r in record)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "container_demo.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time"] + [f"container.{r}" for r in record] + [f"runner.{r}" for r in record])
        for k, t in enumerate(native["time"]):
            w.writerow([t] + [one[r][k] for r in record] + [native[r][k] for r in record])
    print(
        f"{container}: {len(md.modelVariables)} variables, {len(record)} Real outputs, step {h} s, "
        f"{md.generationTool}"
    )
    print(
        f"  fmpy simulate_fmu of the container against rustfmu-runner on {args.system}.ssp, {args.stop} s: "
        f"largest difference of any output {worst:.3g}; alpha1 {one['pendulum.alpha1'][0]} -> {one['pendulum.alpha1'][-1]:.3g} rad"
    )
    assert worst <= 1e-12 * max(1.0, max(float(np.max(np.abs(native[r]))) for r in record)), worst
    fmi3 = fmus / "containers" / "fmi3" / f"{args.system}.fmu"
    if fmi3.exists():
        three = fmpy.simulate_fmu(str(fmi3), stop_time=args.stop, step_size=h, output_interval=h, output=record)
        worst3 = max(float(np.max(np.abs(np.asarray(three[r], float) - np.asarray(native[r], float)))) for r in record)
        same = max(float(np.max(np.abs(np.asarray(three[r], float) - np.asarray(one[r], float)))) for r in record)
        print(
            f"  {fmi3} (FMI 3.0) in fmpy: largest difference {worst3:.3g} against the runner, "
            f"{same:.3g} against the FMI 2.0 container"
        )
        assert worst3 <= 1e-12 * max(1.0, max(float(np.max(np.abs(native[r]))) for r in record)), worst3
    assert abs(native["pendulum.alpha1"][-1]) < 0.05


if __name__ == "__main__":
    main()
