"""Co-simulation of the project's FMUs as an importer sees them: a fixed-step master loop on
fmpy's FMU2Slave (FMI 2.0) and FMU3Slave (FMI 3.0), the two composed systems of the paper (read
from the SSP files fmu-build writes), and their linear reference.

Used by the examples (`examples/composed_demo.py`, `examples/paper_figures.py`) and by the tests
(`tests/python/test_composition.py`), which put `examples/` on sys.path.
"""

from .master import Connection, Component, System, simulate  # noqa: F401
from .systems import (  # noqa: F401
    bind,
    closed_loop_matrices,
    linear_response,
    plant_and_controller,
    plant_motors_controller,
    read_ssp,
    ssp_path,
)
