"""Total Lagrangian Explicit Dynamics: builder, model, state, solver, load curves."""

from .builder import ModelBuilder
from .curves import Constant, LoadCurve, Ramp, SmoothRamp, Hilly, Step, Table
from .model import Model
from .state import State
from .report import ContactReport, PairHistory, RelaxInfo, RunInfo, ToolHistory
from .smoothing import StrainSmoothing
from .solver import Simulation, Solver

__all__ = [
    "ModelBuilder",
    "Model",
    "State",
    "Solver",
    "Simulation",
    "RunInfo",
    "RelaxInfo",
    "ContactReport",
    "ToolHistory",
    "PairHistory",
    "StrainSmoothing",
    "LoadCurve",
    "Constant",
    "Step",
    "Ramp",
    "SmoothRamp",
    "Hilly",
    "Table",
]
