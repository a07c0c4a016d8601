"""NiftySim <SubModel>s (user guide v2.4 §3.7): several models, each with its mesh (listed, or an
<MSHMesh> / <VTKMesh> file with its transforms), element sets and constraints, assembled into one,
as NiftySim does it (tledModel::LoadFromXML with tledSubModelManager): the model's mesh is the
sub-models' meshes one after the other, their element sets offset to the merged element numbering
and their constraints' nodes (and pressure faces) mapped to the merged node numbering, appended
after the model's own element sets and constraints (which refer to the merged mesh); constraint
nodes chosen by normal, "all" or a start index are resolved on the sub-model's own mesh. With
<SubModelNodeMergerDistance> d, each node of a later sub-mesh is the first node already in the
mesh closer than d [m], if there is one (meshes assembled from blocks share their interface
nodes). A sub-model's membranes (<ShellElements> with its <ShellElementSet>s) join the model's
list of membrane triangles after the earlier sub-models' (_sub_membranes).
A sub-model's <SystemParams> is ignored.

The result is an ordinary <Model> element: the importer reads it as it reads any model, with its
checks and messages (the sub-models named in them by their index)."""

from __future__ import annotations

import copy

import xml.etree.ElementTree as ET

import numpy as np

from .niftysim import NiftySimError, _mesh, _numbers, element_set
from .niftysim_elements import as_tets
from .niftysim_membranes import ORIGIN, _facets, _set_members
from .niftysim_geometry import (
    MESH_FILE_TAGS,
    constraint_nodes,
    surface_faces,
    triangles_per_face,
    uses_node_shorthand,
)

__all__ = ["flatten_submodels"]

_SUB_CHILDREN = {"Nodes", "Elements", *MESH_FILE_TAGS, "ElementSet", "Constraint", "SystemParams"}


def flatten_submodels(root: ET.Element, f: str, membranes: bool = True) -> ET.Element:
    """``root`` with its sub-models merged (``root`` itself if it has none), their membranes left
    out if not ``membranes``; errors name the file ``f`` and the sub-model."""
    subs = root.findall("SubModel")
    if not subs:
        return root
    own = root.find("ShellElements")
    if membranes and own is not None and any(sm.find("ShellElements") is not None for sm in subs):
        raise NiftySimError(
            "<ShellElements> in the model and in a sub-model: expected the membranes in one place "
            "(NiftySim takes a sub-model's)",
            f,
            "ShellElements",
        )
    d = _merge_distance(root, f)
    flat = ET.Element("Model", root.attrib)
    for child in root:
        if child.tag not in ("SubModel", "SubModelNodeMergerDistance", "Nodes", "Elements", *MESH_FILE_TAGS):
            flat.append(child)  # the model's own sets and constraints come first (NiftySim appends)
    X_all = np.zeros((0, 3))
    T_all: list[np.ndarray] = []
    etype = None
    shell_faces: list[np.ndarray] = []
    for i, sm in enumerate(subs):
        key = f"SubModel[{i}]"
        for child in sm:
            if child.tag in ("ShellElements", "ShellElementSet"):  # below, or skipped
                continue
            if child.tag not in _SUB_CHILDREN:
                raise NiftySimError(
                    f"<{child.tag}> in a sub-model: NiftySim reads a sub-model's mesh, element "
                    "sets and constraints only; move it to the model",
                    f,
                    f"{key}/{child.tag}",
                )
        X, T, et = _sub_mesh(sm, f, key)
        if etype is not None and et != etype:
            raise NiftySimError(
                f"Elements Type={et}, but an earlier sub-model has {etype}: one element type", f, key
            )
        etype = et
        node_map, X_all = _add_nodes(X_all, X, d)
        first = sum(len(t) for t in T_all)
        T_all.append(node_map[T])
        for k, es in enumerate(sm.findall("ElementSet")):
            flat.append(_offset_set(es, len(T), first, f, f"{key}/ElementSet[{k}]"))
        tets = as_tets(X, T, f, key)[0]  # an H8 sub-model's surfaces are those of its tetrahedra
        for k, c in enumerate(sm.findall("Constraint")):
            flat.append(_mapped_constraint(c, node_map, X, tets, f, f"{key}/Constraint[{k}]"))
        sheet = _sub_membranes(sm, node_map, tets, sum(map(len, shell_faces)), f, key) if membranes else None
        if sheet is not None:
            shell_faces.append(sheet[0])
            flat.extend(sheet[1])
    nodes = ET.SubElement(flat, "Nodes", {"DOF": "3", "NumNodes": str(len(X_all))})
    nodes.text = "\n".join(" ".join(repr(float(v)) for v in x) for x in X_all)
    T = np.concatenate(T_all)
    elements = ET.SubElement(flat, "Elements", {"Type": str(etype), "NumEls": str(len(T))})
    elements.text = "\n".join(" ".join(str(int(v)) for v in t) for t in T)
    if shell_faces:
        F = np.concatenate(shell_faces)
        shells = ET.SubElement(flat, "ShellElements", {"Type": "T3", "NumEls": str(len(F))})
        shells.text = "\n".join(" ".join(str(int(v)) for v in t) for t in F)
    return flat


def _sub_mesh(sm: ET.Element, f: str, key: str):
    """A sub-model's <Nodes> and <Elements> (the importer's reader), its errors naming it."""
    try:
        return _mesh(sm, f)
    except NiftySimError as e:
        where = f + (f" [{e.key}]" if e.key else "")
        raise NiftySimError(str(e)[len(where) + 2 :], f, f"{key}/{e.key}" if e.key else key) from None


def _merge_distance(root, f) -> float:
    """<SubModelNodeMergerDistance> [m], or −1 (no merging) without it."""
    el = root.find("SubModelNodeMergerDistance")
    if el is None:
        return -1.0
    v = _numbers(el, f, "SubModelNodeMergerDistance", float)
    if v.size != 1 or not np.isfinite(v[0]) or v[0] < 0:
        raise NiftySimError(
            "<SubModelNodeMergerDistance>: expected one distance >= 0 [m]", f, "SubModelNodeMergerDistance"
        )
    return float(v[0])


def _add_nodes(X_all: np.ndarray, X: np.ndarray, d: float) -> tuple[np.ndarray, np.ndarray]:
    """Each node of X becomes the first node of the mesh so far closer than d (with d >= 0), else a
    new one. Returns the sub-mesh's node → mesh node map and the mesh's nodes."""
    n0 = len(X_all)
    if d < 0 or n0 == 0:  # NiftySim merges into nodes of earlier sub-meshes only, once there are some
        return np.arange(n0, n0 + len(X)), np.vstack([X_all, X])
    from scipy.spatial import cKDTree

    before = cKDTree(X_all) if n0 else None
    own = cKDTree(X)
    node_map = np.empty(len(X), np.int64)
    added: list[np.ndarray] = []
    for j, x in enumerate(X):
        near = before.query_ball_point(x, d, p=2.0) if before is not None else []
        hits = [i for i in near if np.linalg.norm(X_all[i] - x) < d]
        if hits:
            node_map[j] = min(hits)
            continue
        earlier = [k for k in own.query_ball_point(x, d, p=2.0) if k < j and np.linalg.norm(X[k] - x) < d]
        new_of = [node_map[k] for k in earlier if node_map[k] >= n0]
        if new_of:  # an earlier node of this sub-mesh, itself new
            node_map[j] = min(new_of)
            continue
        node_map[j] = n0 + len(added)
        added.append(x)
    return node_map, np.vstack([X_all, *added]) if added else X_all


def _offset_set(es: ET.Element, M: int, first: int, f: str, key: str) -> ET.Element:
    """A sub-model's element set in the merged numbering (its Size shorthands expanded locally)."""
    return _listed_set(es, "ElementSet", element_set(es, M, f, key) + first)


def _listed_set(es: ET.Element, tag: str, members: np.ndarray, **attrib: str) -> ET.Element:
    """Set ``es`` as a <tag> listing ``members`` (Size their count), with ``es``'s other attributes
    and ``attrib``, and its children (its material) without the text after them."""
    out = ET.Element(tag, {**es.attrib, **attrib, "Size": str(len(members))})
    out.text = " ".join(str(int(m)) for m in members)
    for child in es:
        c = copy.copy(child)
        c.tail = None
        out.append(c)
    return out


def _sub_membranes(sm, node_map, T: np.ndarray, first: int, f: str, key: str):
    """Sub-model ``sm``'s membranes in the merged model: its triangles (F, 3) in the merged node
    numbering (``node_map``: its node → the model's; T (M, 4): its tets, for SURFACE), and its
    <ShellElementSet>s as sets of merged triangles from ``first`` on, each marked with where it
    came from (ORIGIN). None where it has no membranes. As tledSubModelManager merges them into
    one list of facets; Q4 facets are split after the merge's renumbering (as a model written
    whole splits them), and sub-models of different facet kinds merge too (NiftySim refuses that)."""
    shells, sets = sm.findall("ShellElements"), sm.findall("ShellElementSet")
    if not shells and not sets:
        return None
    if len(shells) != 1 or not sets:
        raise NiftySimError(
            f"{len(shells)} <ShellElements> and {len(sets)} <ShellElementSet>: expected one "
            "<ShellElements> and at least one <ShellElementSet> (the membranes' materials)",
            f,
            f"{key}/ShellElements",
        )
    kind = shells[0].get("Type", shells[0].get("type"))
    faces, per = _facets(shells[0], kind, T, len(node_map), f, f"{key}/ShellElements", node_map)
    merged = []
    for k, es in enumerate(sets):
        where = f"{key}/ShellElementSet[{k}]"
        listed = _set_members(es, len(faces) // per, kind, f, where)
        members = first + (per * listed[:, None] + np.arange(per)).ravel()
        merged.append(_listed_set(es, "ShellElementSet", members, **{ORIGIN: where}))
    return faces, merged


def _mapped_constraint(c: ET.Element, node_map, X, T, f: str, key: str) -> ET.Element:
    """A sub-model's constraint with its nodes (or pressure / traction faces) in the merged
    numbering; faces on the sub-model's whole surface or facing a normal become the list of those
    facets, chosen on the sub-model's own surface (as NiftySim resolves it)."""
    out = ET.Element("Constraint", dict(c.attrib))
    for child in c:
        if child.tag in ("Nodes", "Faces"):
            continue
        out.append(child)
    n = len(node_map)

    def mapped(ids: np.ndarray, what: str) -> str:
        if ids.size and (ids.min() < 0 or ids.max() >= n):
            raise NiftySimError(f"<{what}>: node index out of range 0..{n - 1} of its sub-model", f, key)
        return " ".join(str(int(v)) for v in node_map[ids])

    if c.get("Type") in ("Pressure", "Traction"):
        faces, _ = surface_faces(c, X, T, f, key)  # on the sub-model's own surface
        per = triangles_per_face(c)
        mag = out.find("Magnitudes")
        if per > 1 and mag is not None and mag.get("Type") == "DIFFORM":  # a traction per triangle
            v = _numbers(mag, f, f"{key}/Magnitudes")
            m = ET.Element("Magnitudes", dict(mag.attrib))
            t = v.reshape(-1, 3).repeat(per, axis=0) if v.size % 3 == 0 else v  # else named on import
            m.text = " ".join(repr(float(x)) for x in t.ravel())
            out.remove(mag)
            out.append(m)
        for child in [e for e in out if e.tag in ("Normal", "RestrictTo")]:
            out.remove(child)
        fe = ET.SubElement(out, "Faces")
        fe.text = mapped(faces.ravel(), "Faces")
        out.set("NumFaces", str(len(faces)))
        out.set("SpecType", "FACES")
        out.attrib.pop("FaceType", None)
        return out
    nodes = c.find("Nodes")
    if uses_node_shorthand(c):  # chosen on the sub-model's own mesh, as NiftySim resolves it
        ids = constraint_nodes(c, X, T, f, key)
        for child in [e for e in out if e.tag in ("Normal", "RestrictTo")]:
            out.remove(child)
        out.set("SpecType", "NODES")
        out.set("NumNodes", str(ids.size))
        ET.SubElement(out, "Nodes").text = mapped(ids, "Nodes")
    elif nodes is not None:
        ne = ET.SubElement(out, "Nodes", dict(nodes.attrib))
        ne.text = mapped(_numbers(nodes, f, f"{key}/Nodes", np.int64), "Nodes")
    return out
