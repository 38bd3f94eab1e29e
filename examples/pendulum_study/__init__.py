"""Parameter studies of the closed loop (Pendulum, Controller, DCMotor FMUs) on Dask.

`closed_loop`: one co-simulation with FMU instances kept alive and fmi2Reset between runs.
`runner`: run ids, the resumable CSV of results, Dask tasks with a worker plugin, sequential runs.
`studies`: region of attraction and Monte Carlo robustness run specs. `plots`: the PNGs.
The command line is examples/parameter_study.py.
"""
