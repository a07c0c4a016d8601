"""pliant: soft-body simulation by nonlinear finite elements (Total Lagrangian Explicit Dynamics)
on tetrahedra, in SI units (m, kg, s, N, Pa).

    import pliant as pl
    b = pl.ModelBuilder(); b.add_mesh(nodes, tets)
    b.set_material(pl.NeoHookean(E=3e3, nu=0.45), density=1000.0)
    sim = pl.Simulation(b.finalize())
"""

from . import _core, contact, cutting, haptics, io, mesh  # noqa: F401 (sub-packages, re-exported)
from .errors import (
    BackendError,
    ConvergenceError,
    DegenerateElementError,
    FileError,
    InputError,
    InstabilityError,
    InvertedElementError,
    MaterialError,
    MeshError,
    PliantError,
    PliantWarning,
    TimeStepError,
)
from .materials import (
    ArrudaBoyce,
    LinearElastic,
    Material,
    MembraneMaterial,
    MooneyRivlin,
    NeoHookean,
    NeoHookeanCoupled,
    NeoHookeanMembrane,
    Polynomial,
    StVenantKirchhoff,
    StVKMembrane,
    TransverselyIsotropic,
    Viscoelastic,
)
from .tled import (
    Constant,
    ContactReport,
    Model,
    ModelBuilder,
    Ramp,
    RelaxInfo,
    RunInfo,
    Simulation,
    SmoothRamp,
    Hilly,
    Solver,
    State,
    Step,
    StrainSmoothing,
    Table,
    ToolHistory,
    PairHistory,
)


def _version() -> str:
    """The installed distribution's version: one source, pyproject.toml."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pliant")
    except PackageNotFoundError:  # run from a source tree without installing
        return "0+unknown"


__version__ = _version()

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
    "Constant",
    "Step",
    "Ramp",
    "SmoothRamp",
    "Hilly",
    "Table",
    "Material",
    "NeoHookean",
    "MooneyRivlin",
    "NeoHookeanCoupled",
    "StVenantKirchhoff",
    "Polynomial",
    "ArrudaBoyce",
    "TransverselyIsotropic",
    "Viscoelastic",
    "LinearElastic",
    "MembraneMaterial",
    "StVKMembrane",
    "NeoHookeanMembrane",
    "PliantError",
    "InputError",
    "FileError",
    "BackendError",
    "MaterialError",
    "MeshError",
    "InvertedElementError",
    "DegenerateElementError",
    "TimeStepError",
    "InstabilityError",
    "ConvergenceError",
    "PliantWarning",
]
