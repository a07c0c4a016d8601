"""Triangle surface meshes: reading (OBJ read here, robust to texture data; STL, OFF and PLY by
pliant.io.stl, .off and .ply; glTF through trimesh; other formats through meshio), writing, and
primitive surfaces. Vertices [m] (V, 3) float64, faces (F, 3) int64."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..checks import as_real, mesh_arrays, shown
from ..errors import MeshError
from ..io.files import file_problem
from ..io.off import read_off
from ..io.ply import read_ply
from ..io.stl import join_coincident, read_stl
from ..io.vtk_polydata import is_vtk_polydata, read_vtk_polydata


# Files read as surfaces by their suffix (and legacy VTK POLYDATA .vtk by its header): scenes
# tetrahedralize them.
SURFACE_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf")


def _read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    V, F = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for lineno, line in enumerate(f, 1):
            words = line.split()  # any spacing: tabs, indentation, CRLF
            key = words[0] if words else ""
            if key == "v":
                try:
                    V.append([float(x) for x in words[1:4]])
                except ValueError:
                    raise MeshError(f"{path}:{lineno}: bad vertex line {line.strip()[:80]!r}") from None
                if len(V[-1]) != 3:
                    raise MeshError(f"{path}:{lineno}: vertex with {len(V[-1])} coordinates")
            elif key == "f":
                try:
                    idx = [int(t.split("/")[0]) for t in words[1:]]
                except ValueError:
                    raise MeshError(f"{path}:{lineno}: bad face line {line.strip()[:80]!r}") from None
                idx = [i - 1 if i > 0 else len(V) + i for i in idx]
                if len(idx) < 3:
                    raise MeshError(f"{path}:{lineno}: face with {len(idx)} vertices")
                if not all(0 <= i < 2**62 for i in idx):
                    raise MeshError(f"{path}:{lineno}: face index out of range in {line.strip()[:80]!r}")
                for k in range(1, len(idx) - 1):  # fan-triangulate polygons
                    F.append([idx[0], idx[k], idx[k + 1]])
    return np.asarray(V, dtype=float).reshape(-1, 3), np.asarray(F, dtype=np.int64).reshape(-1, 3)


def metres_hint(X: np.ndarray, source: str, remedy: str = "scale it by 0.001") -> str | None:
    """A warning when nodes X [m], (N, 3), span more than 10 m: pliant works in SI metres, and
    a mesh that wide is most likely in millimetres (organs are centimetres across). ``remedy``:
    what the user can do where the mesh is read (a scene: ``set mesh.scale = 0.001``)."""
    extent = float(np.ptp(X, axis=0).max()) if len(X) else 0.0
    if extent <= 10.0:
        return None
    return (
        f"{source}: the mesh is {extent:g} m across; pliant expects SI metres: if the file is in "
        f"millimetres, {remedy}"
    )


def _read_gltf(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A glTF 2.0 file's (.glb, .gltf) triangle meshes, each placed by its node's transform
    (trimesh's scene graph), as one surface; vertices at exactly one position joined (glTF splits
    them where normals or texture coordinates differ). glTF's unit is the metre (glTF 2.0 spec §3.4)."""
    import trimesh

    try:
        m = trimesh.load(path, force="mesh", process=False)
    except Exception as e:  # trimesh raises what its parsers raise
        raise MeshError(f"{path}: cannot read as a glTF surface ({type(e).__name__}: {e})") from None
    if not isinstance(m, trimesh.Trimesh):  # force="mesh" gives one; anything else holds no triangles
        raise MeshError(f"{path}: no triangle mesh in the glTF file")
    V, F = (
        np.asarray(m.vertices, dtype=np.float64).reshape(-1, 3),
        np.asarray(m.faces, np.int64).reshape(-1, 3),
    )
    if len(F) and (F.min() < 0 or F.max() >= len(V)):  # trimesh does not check without process
        raise MeshError(f"{path}: face index out of range 0..{len(V) - 1} (a glTF index accessor)")
    return join_coincident(V, F) if len(F) else (V, F)


def read_surface(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a triangle surface (.obj, .stl (ASCII or binary), .ply, .off, .glb/.gltf, .vtk POLYDATA
    or UNSTRUCTURED_GRID, .vtu... any meshio format with triangles; a legacy VTK grid meshio refuses
    through pliant.io.vtk_grid). Raises MeshError for a missing, unreadable, empty or out-of-range
    mesh."""
    path = Path(path)
    problem = file_problem(path)
    if problem:
        raise MeshError(f"{path}: {problem}")
    suffix = path.suffix.lower()
    if suffix == ".obj":
        V, F = _read_obj(path)
    elif suffix == ".stl":
        V, F = read_stl(path)
    elif suffix in (".glb", ".gltf"):
        V, F = _read_gltf(path)
    elif suffix == ".off":
        V, F = read_off(path)
    elif suffix == ".ply":
        V, F = read_ply(path)
    elif is_vtk_polydata(path):  # legacy VTK surfaces, which meshio does not read
        V, F = read_vtk_polydata(path)
    elif suffix == ".vtp":
        raise MeshError(
            f"{path}: VTK XML PolyData (.vtp) is not read; expected a legacy .vtk (VTK's "
            "vtkPolyDataWriter), .stl, .ply, .obj or .off surface"
        )
    else:
        from ..io.mesh import cell_array, mesh_points
        from ..io.vtk_grid import read_meshio_or_grid

        m = read_meshio_or_grid(path, "surface mesh")
        tris = [cell_array(path, c) for c in m.cells if c.type == "triangle"]
        quads = [cell_array(path, c) for c in m.cells if c.type == "quad"]
        parts = tris + [q[:, [0, 1, 2]] for q in quads] + [q[:, [0, 2, 3]] for q in quads]
        if not parts:
            raise MeshError(
                f"{path}: no triangles (cell types: {', '.join(sorted({c.type for c in m.cells})) or 'none'})"
            )
        V, F = mesh_points(m, path), np.concatenate(parts)
    if len(V) == 0 or len(F) == 0:
        raise MeshError(f"{path}: empty mesh ({len(V)} vertices, {len(F)} faces)")
    if F.min() < 0 or F.max() >= len(V):
        raise MeshError(f"{path}: face index out of range 0..{len(V) - 1}")
    if not np.all(np.isfinite(V)):
        raise MeshError(f"{path}: non-finite vertex coordinates")
    return V, F


def check_surface_output(path) -> Path:
    """``path`` as a surface file pliant can write (a meshio format or .glb) in a writable folder;
    InputError naming it otherwise. Commands check it before their work."""
    from ..io.files import check_output_file

    glb = Path(path).suffix.lower() == ".glb"
    return check_output_file(path, "surface mesh", mesh_format=not glb)


def write_surface(path, V: np.ndarray, F: np.ndarray) -> None:
    """Write a triangle surface in any meshio format (by extension), or binary glTF (.glb, through
    trimesh: float32 positions), atomically. An unwritable path or an unknown extension raises
    InputError naming the path."""
    import meshio

    from ..io.files import atomic_write

    V, F = mesh_arrays(V, F, 3, "write_surface", cell="face")
    path = check_surface_output(path)
    if path.suffix.lower() == ".glb":
        import trimesh

        glb = trimesh.Trimesh(V, F, process=False).export(file_type="glb")
        assert isinstance(glb, bytes)  # a .glb export is one blob
        atomic_write(path, lambda tmp: Path(tmp).write_bytes(glb), "surface mesh")
        return
    atomic_write(path, lambda tmp: meshio.write(tmp, meshio.Mesh(V, [("triangle", F)])), "surface mesh")


def primitive_surface(kind: str, **p) -> tuple[np.ndarray, np.ndarray]:
    """Closed, outward-oriented triangle surfaces [m]: sphere(radius), cylinder(radius, height; axis
    z, centred), torus(major_radius, minor_radius; axis z). Resolution follows ``segments``
    (boxes: pliant.mesh.box_tets)."""
    import trimesh

    needs = {
        "sphere": ("radius",),
        "cylinder": ("radius", "height"),
        "torus": ("major_radius", "minor_radius"),
    }
    if not isinstance(kind, str) or kind not in needs:
        raise MeshError(f"unknown primitive {shown(kind)}; expected sphere, cylinder or torus")
    missing = [key for key in needs[kind] if key not in p]
    if missing:
        raise MeshError(f"{kind}: give {' and '.join(missing)} [m]")
    for key, low, high in (("segments", 3, 4096), ("minor_segments", 3, 4096), ("subdivisions", 0, 7)):
        if key in p and not (isinstance(p[key], (int, np.integer)) and low <= p[key] <= high):
            raise MeshError(f"{kind}: {key} = {p[key]!r}; expected an integer from {low} to {high}")
    for key in ("radius", "height", "major_radius", "minor_radius"):
        if key in p and not (math.isfinite(as_real(p[key])) and p[key] > 0):
            raise MeshError(f"{kind}: {key} = {p[key]!r}; expected a finite length > 0 [m]")
    if kind == "torus" and not p["minor_radius"] < p["major_radius"]:
        raise MeshError(
            f"torus: minor_radius {p['minor_radius']} must be smaller than major_radius "
            f"{p['major_radius']} [m]"
        )
    if kind == "sphere":
        m = trimesh.creation.icosphere(subdivisions=int(p.get("subdivisions", 3)), radius=p["radius"])
    elif kind == "cylinder":
        m = trimesh.creation.cylinder(
            radius=p["radius"], height=p["height"], sections=int(p.get("segments", 48))
        )
    else:
        m = trimesh.creation.torus(
            major_radius=p["major_radius"],
            minor_radius=p["minor_radius"],
            major_sections=int(p.get("segments", 48)),
            minor_sections=int(p.get("minor_segments", 24)),
        )
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
