"""A simulation job, whatever file it came from (a scene, a NiftySim model): the builder that holds
mesh, materials, constraints, loads and tools, and the settings of the run (duration, time step,
precision, backend, outputs). Importers produce it; ``pliant.runner`` runs it."""

from __future__ import annotations

from dataclasses import dataclass, field

from .tled import ModelBuilder

__all__ = ["Scene"]


@dataclass
class Scene:
    """A validated job: builder (mesh, materials, constraints, loads, tools) plus run settings."""

    source: str
    builder: ModelBuilder
    duration: float = 1.0  # [s]
    dt: float | None = None  # [s]; None: safety × critical
    safety: float = 0.8
    dtype: str = "float32"
    backend: str = "cpu"
    threads: int | None = None
    static: bool = False
    tol: float = 1e-5
    increments: int = 1
    check_every: int = 16
    output_every: int | None = None  # steps
    output_interval: float | None = None  # [s]
    frames: int = 20
    png: bool = True
    fields: tuple = ("displacement", "velocity", "von_mises", "J", "strain_energy_density")
    title: str = ""
    warnings: list[str] = field(default_factory=list)
    meta: dict = field(default_factory=dict)
