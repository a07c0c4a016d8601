"""NiftySim geometry given by reference rather than listed: a model's (or a sub-model's) mesh read
from a file, <MSHMesh> (Gmsh) or <VTKMesh> (VTK unstructured grid), with its Rotation, ScaleFactor
and Translation (user guide v2.4 §3.3; tledMesh, tledBasicMeshFileReader, tledMeshLoader); and the
nodes of a constraint chosen other than by a full list (§3.5.2; tledModel::GetConstraintInd):
SpecType="NORMAL" (the vertices of the boundary facets within ToleranceAngle of a <Normal>, kept
where they lie inside every <RestrictTo> box and sphere), NumNodes="all", and NumNodes="n" with one
listed index (n consecutive nodes from it); and the surface loads (§3.5.4), Pressure and
Traction, on listed faces, the whole surface or the facets facing a normal."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import InputError, MeshError
from .files import MISSING, file_problem
from .niftysim import NiftySimError, _numbers, _scalar, facets_facing

__all__ = [
    "MESH_FILE_TAGS",
    "constraint_nodes",
    "mesh_file",
    "normal_spec",
    "surface_faces",
    "surface_load",
    "uses_node_shorthand",
]

# Elements given by a file instead of <Nodes> and <Elements>.
MESH_FILE_TAGS = ("MSHMesh", "VTKMesh")


def mesh_file(el, f: str) -> tuple[np.ndarray, np.ndarray, str]:
    """<MSHMesh Type="T4|T4ANP">path ...</MSHMesh> (or <VTKMesh>): nodes (N, 3) [file units, read as
    m] after its transforms, tets (M, 4) in the file's node numbering, and the element type. The
    path is taken relative to the model file's folder, then (as NiftySim takes it) to the working
    folder."""
    key = el.tag
    etype = el.get("Type")
    if etype not in ("T4", "T4ANP", "H8"):
        raise NiftySimError(f"<{key} Type={etype!r}>: expected T4, T4ANP or H8", f, key)
    name = (el.text or "").strip()
    if not name:
        raise NiftySimError(f"<{key}> names no mesh file", f, key)
    here = Path(f).parent / name
    path = Path(name) if file_problem(here) == MISSING and not Path(name).is_absolute() else here
    problem = file_problem(path)
    if problem == MISSING:
        raise NiftySimError(
            f"<{key}> mesh file {name!r}: not found beside the model ({here}) nor in the working folder",
            f,
            key,
        )
    if problem:
        raise NiftySimError(f"<{key}> mesh file {name!r}: {path}: {problem}", f, key)
    try:
        X, T = _file_cells(path, "hexahedron" if etype == "H8" else "tetra", f"<{key} Type={etype}>")
    except MeshError as e:
        raise NiftySimError(str(e), f, key) from None
    return _transformed(X, el, f, key), T, etype


def _file_cells(path: Path, kind: str, what: str) -> tuple[np.ndarray, np.ndarray]:
    """A mesh file's nodes (N, 3) and its cells of ``kind`` (meshio's name), in file order: the
    element numbering the model's sets use. A file whose volume cells are of another kind is
    refused (NiftySim reads the type the model names)."""
    from .mesh import SURFACE_CELLS, cell_array, mesh_points
    from .vtk_grid import read_meshio_or_grid

    mesh = read_meshio_or_grid(path, "volume mesh")
    other = sorted({c.type for c in mesh.cells} - {kind} - SURFACE_CELLS)
    blocks = [cell_array(path, c) for c in mesh.cells if c.type == kind]
    if other or not blocks:
        found = ", ".join(sorted({c.type for c in mesh.cells})) or "none"
        raise MeshError(f"{path}: cells {found}; {what} expects {kind} cells only")
    return mesh_points(mesh, path), np.concatenate(blocks)


def _transformed(X: np.ndarray, el, f: str, key: str) -> np.ndarray:
    """x' = s (R (x − c) + c) + t: <Rotation> cx cy cz αx αy αz (centre [m], angles [°]; R = Rx(αx)
    Ry(αy) Rz(αz), tledBasicMeshFileReader::AssembleRotationMatrix), then <ScaleFactor> s, then
    <Translation> t [m] (the user guide's order: rotation, scaling, translation)."""
    rot = el.find("Rotation")
    if rot is not None:
        r = _numbers(rot, f, f"{key}/Rotation")
        if r.size != 6:
            raise NiftySimError(
                f"<Rotation>: {r.size} numbers; expected 6 (centre cx cy cz, then angles about x, y, z "
                "in degrees)",
                f,
                f"{key}/Rotation",
            )
        c = r[:3]
        X = (X - c) @ _rotation(*np.radians(r[3:])).T + c
    scale = el.find("ScaleFactor")
    if scale is not None:
        X = X * _scalar(scale.text, f, f"{key}/ScaleFactor", float, 0.0)
    move = el.find("Translation")
    if move is not None:
        t = _numbers(move, f, f"{key}/Translation")
        if t.size != 3:
            raise NiftySimError(f"<Translation>: {t.size} numbers; expected 3 [m]", f, f"{key}/Translation")
        X = X + t
    return X


def _rotation(ax: float, ay: float, az: float) -> np.ndarray:
    """Rx(ax) Ry(ay) Rz(az), angles [rad] about the coordinate axes."""
    cx, sx, cy, sy, cz, sz = (
        math.cos(ax),
        math.sin(ax),
        math.cos(ay),
        math.sin(ay),
        math.cos(az),
        math.sin(az),
    )
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    return rx @ ry @ rz


def normal_spec(c, f: str, key: str) -> tuple[np.ndarray, float]:
    """A SpecType="NORMAL" constraint's <Normal ToleranceAngle="deg">: the normal and the angle
    [°] (both required, the angle in [0, 180], as NiftySim's _LoadNormalSpec asks)."""
    nrm = c.find("Normal")
    if nrm is None:
        raise NiftySimError(
            'SpecType="NORMAL" needs <Normal ToleranceAngle="degrees">nx ny nz</Normal>', f, key
        )
    n = _numbers(nrm, f, f"{key}/Normal")
    if n.size != 3 or not np.linalg.norm(n) > 0:
        raise NiftySimError("<Normal>: expected a non-zero vector of 3 numbers", f, f"{key}/Normal")
    if nrm.get("ToleranceAngle") is None:
        raise NiftySimError("<Normal> lacks ToleranceAngle (degrees)", f, f"{key}/Normal")
    angle = _scalar(nrm.get("ToleranceAngle"), f, f"{key}/Normal ToleranceAngle", float, 0.0, False)
    if angle > 180.0:
        raise NiftySimError(
            f"<Normal ToleranceAngle={angle:g}>: expected 0 to 180 degrees", f, f"{key}/Normal"
        )
    return n, angle


def uses_node_shorthand(c) -> bool:
    """Whether a constraint's nodes need the mesh to be known (NORMAL, all, or a start index)."""
    num = c.get("NumNodes")
    listed = c.find("Nodes")
    one = listed is not None and len((listed.text or "").split()) == 1
    return c.get("SpecType") == "NORMAL" or num == "all" or (one and num not in (None, "1"))


def constraint_nodes(c, X: np.ndarray, T: np.ndarray, f: str, key: str) -> np.ndarray:
    """The nodes of a Fix / Disp / Force constraint (indices into X, the mesh's nodes [m]; T its
    tets): listed (<Nodes>, NumNodes checked), all, n from a start index, or by surface normal
    (sorted, as NiftySim's MakeSortedUnique leaves them, for DIFFORM magnitudes)."""
    spec = c.get("SpecType", "NODES")
    if spec == "NORMAL":
        from ..mesh.topology import boundary_faces

        n, angle = normal_spec(c, f, key)
        ids = np.unique(facets_facing(X, boundary_faces(T)[0], n, angle))
        ids = _restricted(ids, c, X, f, key)
        if ids.size == 0:
            raise NiftySimError(
                f"no boundary node is on a facet within {angle:g}° of <Normal> {n.tolist()} "
                "(inside its <RestrictTo>)",
                f,
                key,
            )
        return ids
    if spec != "NODES":
        raise NiftySimError(f"SpecType={spec!r}: expected NODES or NORMAL", f, key)
    num = c.get("NumNodes")
    if num == "all":
        return np.arange(len(X))
    nodes_el = c.find("Nodes")
    if nodes_el is None:
        raise NiftySimError('<Constraint> without <Nodes> (nor NumNodes="all" or SpecType="NORMAL")', f, key)
    ids = _numbers(nodes_el, f, f"{key}/Nodes", np.int64)
    if ids.size == 0:
        raise NiftySimError("<Nodes> lists no node", f, f"{key}/Nodes")
    if num is None:
        return ids
    count = int(_scalar(num, f, f"{key} NumNodes", int, 0, False))
    if ids.size == 1 and count > 1:  # NiftySim: one index = the first of NumNodes consecutive nodes
        if not 0 <= ids[0] <= len(X) - count:
            raise NiftySimError(
                f"NumNodes={count} from node {ids[0]}: past the mesh's {len(X)} nodes", f, f"{key}/Nodes"
            )
        return ids[0] + np.arange(count)
    if ids.size != count:
        raise NiftySimError(f"NumNodes={count} but {ids.size} nodes listed", f, key)
    return ids


def _restricted(ids: np.ndarray, c, X: np.ndarray, f: str, key: str) -> np.ndarray:
    """ids kept where the node lies in every <RestrictTo Type="Box"> (min_x max_x min_y max_y
    min_z max_z [m], bounds included) and <RestrictTo Type="Sphere"> (radius, centre [m]; strictly
    inside): tledBoxNodeRejector, tledSphereNodeRejector."""
    for k, r in enumerate(c.findall("RestrictTo")):
        where = f"{key}/RestrictTo[{k}]"
        v = _numbers(r, f, where)
        x = X[ids]
        kind = r.get("Type")
        if kind == "Box" and v.size == 6:
            lo, hi = v[0::2], v[1::2]
            ids = ids[np.all((x >= lo) & (x <= hi), axis=1)]
        elif kind == "Sphere" and v.size == 4:
            ids = ids[np.linalg.norm(x - v[1:], axis=1) < v[0]]
        else:
            raise NiftySimError(
                f'<RestrictTo Type={kind!r}> with {v.size} numbers; expected Type="Box" (min_x max_x '
                'min_y max_y min_z max_z) or Type="Sphere" (radius cx cy cz)',
                f,
                where,
            )
    return ids


def surface_faces(c, X: np.ndarray, T: np.ndarray, f: str, key: str) -> tuple[np.ndarray, bool]:
    """The triangles (F, 3) of a Pressure or Traction constraint: the boundary facets within
    ToleranceAngle of <Normal> (SpecType="NORMAL"), the whole boundary (NumFaces="all"), or the
    listed <Faces> (NumFaces checked, FaceType Tri); and whether they are boundary facets with
    the mesh's outward winding (False: as listed)."""
    from ..mesh.topology import boundary_faces

    ctype = c.get("Type")
    if c.get("SpecType", "NODES") == "NORMAL":
        n, angle = normal_spec(c, f, key)
        faces, orient = facets_facing(X, boundary_faces(T)[0], n, angle), True
    elif c.get("NumFaces") == "all":
        faces, orient = boundary_faces(T)[0], True
    else:
        kind = c.get("FaceType", "Tri")
        if kind not in ("Tri", "Quad"):
            raise NiftySimError(f"FaceType={kind!r}: expected Tri (T4 meshes) or Quad (H8 meshes)", f, key)
        fe = c.find("Faces")
        if fe is None:
            raise NiftySimError(f'{ctype} needs <Faces>, NumFaces="all" or SpecType="NORMAL"', f, key)
        faces = _numbers(fe, f, f"{key}/Faces", np.int64)
        corners = 3 if kind == "Tri" else 4
        if faces.size % corners:
            raise NiftySimError(
                f"<Faces FaceType={kind}>: {faces.size} indices, not a multiple of {corners}", f, key
            )
        faces, orient = faces.reshape(-1, corners), False
        num = c.get("NumFaces")
        if num is not None and num.isdigit() and int(num) != len(faces):
            raise NiftySimError(f"NumFaces={num} but {len(faces)} faces listed", f, key)
        if kind == "Quad":  # each as two triangles, cut as the tetrahedra beside it are
            from ..mesh.split import split_quads

            faces = split_quads(faces)
    if len(faces) == 0:
        raise NiftySimError(f"{ctype}: no faces selected", f, key)
    return faces, orient


def triangles_per_face(c) -> int:
    """2 where a Pressure or Traction constraint lists quadrilateral faces (FaceType="Quad", H8
    meshes: surface_faces gives two triangles for each, in order), else 1."""
    listed = c.get("SpecType", "NODES") != "NORMAL" and c.get("NumFaces") != "all"
    return 2 if listed and c.get("FaceType") == "Quad" else 1


def surface_load(c, b, T: np.ndarray, shapes: dict, f: str, key: str, unsupported) -> None:
    """<Constraint Type="Pressure"> (a follower pressure, tledPressureConstraint: one <Magnitude>
    [Pa], positive against the facet normal (x1 − x0) × (x2 − x0)) or Type="Traction"
    (tledTractionConstraint: <Magnitudes Type="UNIFORM"> tx ty tz, or DIFFORM, three per facet
    [Pa], on each facet's current area) on surface_faces. NiftySim applies a traction against its
    vector (the force on a facet is −|a| t; its unit test testTractionConstraint checks that sum),
    so pliant adds the traction −t."""
    shape = c.get("LoadShape")
    if shape not in shapes:
        unsupported(f"LoadShape={shape}", "pliant imports RAMP, STEP, POLY345, HILLY and RAMPHOLD")
        return
    pressure = c.get("Type") == "Pressure"
    tag = "Magnitude" if pressure else "Magnitudes"
    mag = c.find(tag)
    if mag is None:
        what = "one value [Pa]" if pressure else 'Type="UNIFORM" tx ty tz, or DIFFORM per face [Pa]'
        raise NiftySimError(f"{c.get('Type')} needs <{tag}> ({what})", f, key)
    mtype = mag.get("Type", "UNIFORM")
    if not pressure and mtype not in ("UNIFORM", "DIFFORM"):
        unsupported(f"Magnitudes Type={mtype}", "pliant imports UNIFORM and DIFFORM")
        return
    v = _numbers(mag, f, f"{key}/{tag}")
    faces, orient = surface_faces(c, b.nodes, T, f, key)
    try:
        if pressure:
            if v.size != 1:
                raise NiftySimError(f"<Magnitude>: expected one value, got {v.size}", f, f"{key}/{tag}")
            b.add_pressure(faces, float(v[0]), shapes[shape](), orient=orient)
            return
        per = triangles_per_face(c)
        want = 3 if mtype == "UNIFORM" else 3 * len(faces) // per
        if v.size != want:
            raise NiftySimError(
                f"<Magnitudes Type={mtype}>: {v.size} values; expected {want} (tx ty tz"
                + (")" if mtype == "UNIFORM" else f" for each of the {len(faces) // per} faces)"),
                f,
                f"{key}/{tag}",
            )
        t = -v.reshape(-1, 3).repeat(per, axis=0) if mtype == "DIFFORM" else -v
        b.add_traction(faces, t, shapes[shape]())
    except InputError as e:
        raise NiftySimError(str(e), f, key) from None
