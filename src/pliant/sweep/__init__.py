"""Sweeps: many runs of one scene or NiftySim model with parameters varied by key path (grids,
lists, Latin hypercube, Sobol' and Saltelli designs), on Dask from a laptop to a cluster,
resumable, with a results table, an optional fields dataset and Sobol sensitivity indices.
See docs/sweeps.md."""

from .analyze import sobol_indices, write_sensitivity
from .case import SceneCase
from .design import design_runs, salib_problem
from .execute import SweepError, execute, records_table, run_one
from .run import SweepResult, run_sweep
from .spec import Design, Outputs, Parameter, SweepSpec, load_sweep

__all__ = [
    "Design",
    "Outputs",
    "Parameter",
    "SceneCase",
    "SweepError",
    "SweepResult",
    "SweepSpec",
    "design_runs",
    "execute",
    "load_sweep",
    "records_table",
    "run_one",
    "run_sweep",
    "salib_problem",
    "sobol_indices",
    "write_sensitivity",
]
