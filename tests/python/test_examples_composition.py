"""The composed demo script writes its CSV and plot, and its pendulum ends upright."""

import csv
import pathlib
import subprocess
import sys

from conftest import FMU_DIR, fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_composed_demo_writes_csv_and_png(tmp_path):
    fmu("DCMotor")
    r = subprocess.run(
        [sys.executable, str(ROOT / "examples/composed_demo.py"), "--out", str(tmp_path), "--fmu-dir", str(FMU_DIR)],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, f"composed_demo.py failed:\n{r.stdout}\n{r.stderr}"
    assert (tmp_path / "composed_demo.png").stat().st_size > 10_000
    with open(tmp_path / "composed_demo.csv") as f:
        rows = list(csv.reader(f))
    header, last = rows[0], rows[-1]
    assert header[0] == "time [s]" and "pendulum.alpha1 [rad]" in header
    assert float(last[0]) == 8.0 and len(rows) == 8002
    for name in ("pendulum.alpha1 [rad]", "pendulum.alpha2 [rad]"):
        assert abs(float(last[header.index(name)])) < 1e-3, f"{name} did not settle: {last[header.index(name)]}"
