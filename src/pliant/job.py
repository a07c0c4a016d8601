"""A simulation job, whatever file it came from (a scene, a NiftySim model): the builder that holds
mesh, materials, constraints, loads and tools, and the settings of the run (duration, time step,
precision, backend, outputs). Importers produce it; ``pliant.runner`` runs it."""

from __future__ import annotations

from dataclasses import dataclass, field

from .errors import InputError
from .mesh.surface import SURFACE_SUFFIXES
from .tled import ModelBuilder

__all__ = ["Scene", "load_job", "parse_overrides"]


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
    blades: list = field(default_factory=list)  # pliant.cutting.Blade: they cut while it runs
    node_sets: dict = field(default_factory=dict)  # name → node indices, from the mesh files
    points: dict = field(default_factory=dict)  # probes: name → node, its displacement per frame


def load_job(path, ignore=None, overrides: dict | None = None) -> Scene:
    """A scene (.toml) or a NiftySim model (.xml) as a :class:`Scene`. ``ignore``: unsupported
    NiftySim features to skip; ``overrides``: key path → value set before validation (scene keys
    as in :mod:`pliant.scene.keys`, NiftySim element paths as in ``set_xml_key``)."""
    from pathlib import Path

    path = Path(path)
    if path.suffix.lower() == ".xml":
        from .io.niftysim import load_niftysim

        return load_niftysim(path, tuple(ignore or ()), overrides)
    from .scene import SceneError, load_scene

    if path.suffix.lower() in MESH_SUFFIXES:
        raise SceneError(
            f"a mesh ({path.suffix}), not a scene: expected a scene (.toml) whose [mesh] file names it "
            "(docs/scenes.md) or a NiftySim model (.xml); `pliant mesh check` and `pliant mesh "
            "quality` read meshes",
            str(path),
        )
    return load_scene(path, overrides)


# Mesh files that `pliant run` and `pliant view` may be handed by mistake for a scene.
MESH_SUFFIXES = {".vtk", ".vtu", ".vtp", ".msh", ".mesh", ".inp", ".xdmf", *SURFACE_SUFFIXES}


def parse_overrides(items) -> dict:
    """``KEY=VALUE`` strings (the command line's ``--set``) as overrides for :func:`load_job`:
    the value read as a TOML value (``1e-4``, ``[0, 0, -9.81]``, ``true``, ``"text"``), a bare
    word as a string. InputError naming the item if it has no ``=`` or no key."""
    from .scene.schema import tomllib

    out: dict = {}
    for item in items or ():
        key, sep, text = str(item).partition("=")
        if not sep or not key.strip() or not text.strip():
            raise InputError(f"--set {item!r}: expected KEY=VALUE (e.g. solver.dt=1e-4)")
        try:
            out[key.strip()] = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = text.strip()
    return out
