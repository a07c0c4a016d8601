"""NiftySim membranes (user guide v2.4 §3.6; tledModel::GetShellMaterial): <ShellElements> —
triangles listed (Type="T3"), quadrilaterals listed (Type="Q4", each split in two along its
diagonal through its smallest node) or the solid mesh's whole boundary (Type="SURFACE") — and
their <ShellElementSet>s, each a set of them (listed, Size="all", or Size consecutive ones from
the one listed) with a <Material>: "Linear" (E ν; pliant's StVKMembrane, NiftySim's geometrically
linear membrane at small displacement) or "NeoHookean" (μ; NeoHookeanMembrane, the same
incompressible membrane), with <Density> and <Thickness>; "LinearShell" (E ν E_b ν_b, NiftySim's
rotation-free shell triangle: a linear membrane that also bends with E_b, ν_b) is StVKMembrane with
``bending=E_b, bending_nu=ν_b`` (without bending, E_b = 0, as most of NiftySim's shell test models,
a plain membrane; with E = 0 a sheet that only bends, as membrane_static_shell_1x1.xml), its set's
<ClampedNodes> (listed, or NumNodes consecutive ones from the one listed) clamping the boundary
edges between them. "LinearThickShell" (transverse shear) is refused
by name.
A <SubModel>'s membranes are merged into the model first (niftysim_submodels.py), their sets
marked with where they came from (ORIGIN), for the messages."""

from __future__ import annotations

import numpy as np

from ..materials.membrane import NeoHookeanMembrane, StVKMembrane
from ..mesh.primitives import triangle_measures
from ..mesh.split import split_quads
from ..mesh.topology import boundary_faces
from ..tled import ModelBuilder

__all__ = ["add_membranes", "ORIGIN"]

# Set on a <ShellElementSet> the sub-model merge wrote (niftysim_submodels.py): where it came from,
# for the messages.
ORIGIN = "pliant-origin"


def add_membranes(root, b: ModelBuilder, T: np.ndarray, f: str, unsupported, warnings: list[str]) -> bool:
    """The model's membranes onto the builder ``b`` (its tets T (M, 4) give SURFACE's facets);
    ``unsupported(name, why)`` refuses (or, when ignored, skips) a feature by name. Returns whether
    a set of NiftySim's shell triangles (LinearShell) became membranes: their step may need dividing."""
    from .niftysim import NiftySimError

    shells, sets = root.findall("ShellElements"), root.findall("ShellElementSet")
    if not shells and not sets:
        return False
    if len(shells) != 1 or not sets:
        raise NiftySimError(
            f"{len(shells)} <ShellElements> and {len(sets)} <ShellElementSet>: expected one "
            "<ShellElements> and at least one <ShellElementSet> (the membranes' materials)",
            f,
            "ShellElements",
        )
    kind = shells[0].get("Type", shells[0].get("type"))  # NiftySim's own models write type="SURFACE"
    faces, per_listed = _facets(shells[0], kind, T, b.n_nodes, f)
    owner = np.full(len(faces), -1, np.int64)
    shells_as_membranes = False
    for k, es in enumerate(sets):
        key = es.get(ORIGIN, f"ShellElementSet[{k}]")
        material = _material(es, f, key, unsupported, warnings)
        listed = _set_members(es, len(faces) // per_listed, kind, f, key)
        members = (per_listed * listed[:, None] + np.arange(per_listed)).ravel()
        clash = members[owner[members] >= 0]
        if clash.size:
            raise NiftySimError(
                f"shell element {int(clash[0]) // per_listed} is also in ShellElementSet[{owner[clash[0]]}]; "
                "expected each in one set",
                f,
                key,
            )
        owner[members] = k
        if material is not None:
            from .niftysim import _named

            with _named(f, key):
                b.add_membrane(
                    faces[members], material, _clamped(es, b.n_nodes, f, key) if material.bends else None
                )
            mtype = es.find("Material").get("Type")
            if mtype == "Linear":  # not LinearShell: its forces have A h
                warnings.append(_linear_note(f, key, b.nodes, faces[members], material.thickness))
            shells_as_membranes |= mtype == "LinearShell"
    if np.any(owner < 0):
        raise NiftySimError(
            f"shell element {int(np.argmax(owner < 0)) // per_listed} is in no <ShellElementSet>: "
            "expected a material for every membrane",
            f,
            "ShellElementSet",
        )
    return shells_as_membranes


def _linear_note(f: str, key: str, X: np.ndarray, F: np.ndarray, h: float) -> str:
    """The warning for a set of NiftySim "Linear" membranes: NiftySim's forces for them
    (tledElementMembraneSimpleLinear::ComputeForces on the CPU, _ComputeForces on the GPU) multiply
    the stress by neither the facet's area A nor the thickness h, as its NeoHookean membrane's do, so
    its Linear membranes are 1/(A h) [1/m³] times stiffer than their E and h say; pliant's are as
    written (docs/scenes.md: on models/box_membrane.xml, E × 1/(A h) reproduces NiftySim's result)."""
    area = triangle_measures(X, F)[0]
    scale = 1.0 / (area * h)
    return (
        f"{f}: {key}: NiftySim's Linear membranes are 1/(A h) times stiffer than their E and h say "
        f"(its forces leave out the facet's area A and thickness h): here {scale.min():.4g} to "
        f"{scale.max():.4g}; pliant's are as written, so results differ from NiftySim's (multiply E by "
        "that factor to reproduce them)"
    )


def _facets(
    el, kind: str | None, T: np.ndarray, n_nodes: int, f: str, key: str = "ShellElements", node_map=None
) -> tuple[np.ndarray, int]:
    """The membrane triangles (F, 3) of <ShellElements> (its node numbers through ``node_map``,
    a sub-model's into the merged model's, where given), and how many triangles each listed
    facet became (2 for Q4)."""
    from .niftysim import NiftySimError, _numbers

    mapped = (lambda F: F) if node_map is None else (lambda F: np.asarray(node_map)[F])
    if kind == "SURFACE":
        if (el.text or "").strip():
            raise NiftySimError(
                'Type="SURFACE" takes the mesh\'s boundary: expected no facets listed', f, key
            )
        return mapped(boundary_faces(T)[0]), 1
    if kind not in ("T3", "Q4"):
        raise NiftySimError(f"<ShellElements Type={kind!r}>: expected T3, Q4 or SURFACE", f, key)
    width = 3 if kind == "T3" else 4
    v = _numbers(el, f, key, np.int64)
    if v.size == 0 or v.size % width:
        raise NiftySimError(
            f"<ShellElements Type={kind}> holds {v.size} node numbers; expected {width} per facet", f, key
        )
    F = v.reshape(-1, width)
    declared = el.get("NumEls")
    if declared is not None and declared.strip() != str(len(F)):
        raise NiftySimError(
            f'<ShellElements NumEls="{declared[:20]}"> lists {len(F)} facets; expected as many as it '
            "declares",
            f,
            key,
        )
    bad = np.nonzero((F < 0) | (F >= n_nodes))
    if bad[0].size:
        i, j = int(bad[0][0]), int(bad[1][0])
        raise NiftySimError(
            f"shell element {i} refers to node {int(F[i, j])}; the model has nodes 0..{n_nodes - 1}", f, key
        )
    return (mapped(F), 1) if kind == "T3" else (split_quads(mapped(F)), 2)


def _set_members(es, n: int, kind: str | None, f: str, key: str) -> np.ndarray:
    """The listed facets of a <ShellElementSet> among n (element_set's forms)."""
    from .niftysim import NiftySimError, element_set

    members = element_set(es, n, f, key)
    if kind == "SURFACE" and es.get("Size", "") != "all":
        raise NiftySimError(
            'with <ShellElements Type="SURFACE"> the facets come in no fixed order (user guide §3.6.1): '
            'expected Size="all"',
            f,
            key,
        )
    return np.asarray(members, np.int64)


def _params(m, f: str, key: str) -> np.ndarray:
    """A shell set's <Material> parameters: its own text, as NiftySim reads them, or an
    <ElasticParams> child, as solids have it."""
    from .niftysim import _numbers, elastic_params

    ep = m.find("ElasticParams")
    return _numbers(m, f, f"{key}/Material") if ep is None else elastic_params(ep, f, f"{key}/Material")


def _material(es, f: str, key: str, unsupported, warnings: list[str]):
    """The membrane material of a <ShellElementSet>, or None where an unsupported one is ignored."""
    from .niftysim import NiftySimError, _scalar, _named

    m = es.find("Material")
    if m is None:
        raise NiftySimError("<ShellElementSet> without <Material>", f, key)
    mtype = m.get("Type")
    if mtype == "LinearThickShell":
        unsupported(
            f"ShellElementSet Material Type={mtype}",
            "thick shells (transverse shear) are not implemented (LinearShell's thin shells are); "
            "skipping the set leaves its facets without a membrane",
        )
        warnings.append(f"{f}: {key}: its shell elements skipped (no membrane)")
        return None
    if mtype not in ("Linear", "NeoHookean", "LinearShell"):
        raise NiftySimError(
            f"<Material Type={mtype!r}> in a shell element set: expected Linear, NeoHookean (membranes), "
            "LinearShell (thin shells) or LinearThickShell (not implemented)",
            f,
            f"{key}/Material",
        )
    sheet = {}
    for name in ("Density", "Thickness"):
        child = m.find(name)
        if child is None:
            raise NiftySimError(
                f"<{name}> is missing: a membrane needs its density and thickness", f, f"{key}/Material"
            )
        sheet[name] = _scalar(child.text, f, f"{key}/Material/{name}", float, 0.0)
    vals = _params(m, f, key)
    want = {"Linear": 2, "NeoHookean": 1, "LinearShell": 4}[mtype]
    if vals.size != want:
        names = {"Linear": "E, nu", "NeoHookean": "mu", "LinearShell": "E, nu, E_b, nu_b"}[mtype]
        raise NiftySimError(
            f"{mtype} takes {want} parameter(s) ({names}); got {vals.size}", f, f"{key}/Material"
        )
    bends = mtype == "LinearShell" and vals[2] != 0.0  # E_b
    if es.find("ClampedNodes") is not None and not bends:
        warnings.append(f"{f}: {key}: <ClampedNodes> ignored: a membrane has no bending to clamp")
    if bends and vals[0] == 0.0:
        warnings.append(
            f"{f}: {key}: LinearShell with E = 0 only bends: nothing holds the sheet in its plane "
            '(loaded across, it drifts there at second order in its slope; docs/engine.md, "Bending")'
        )
    with _named(f, f"{key}/Material"):
        if mtype == "LinearShell" and bends:
            return StVKMembrane(
                vals[0], vals[1], sheet["Thickness"], sheet["Density"], bending=vals[2], bending_nu=vals[3]
            )
        if mtype in ("Linear", "LinearShell"):
            return StVKMembrane(vals[0], vals[1], sheet["Thickness"], sheet["Density"])
        return NeoHookeanMembrane(vals[0], sheet["Thickness"], sheet["Density"])


def _clamped(es, n_nodes: int, f: str, key: str) -> np.ndarray:
    """The nodes a shell set's <ClampedNodes> list (each its nodes, or NumNodes consecutive ones
    from the one listed: tledModel::GetClampedShellNodes)."""
    from .niftysim import NiftySimError, _numbers

    out = [np.zeros(0, np.int64)]
    for k, el in enumerate(es.findall("ClampedNodes")):
        where = f"{key}/ClampedNodes[{k}]"
        v = _numbers(el, f, where, np.int64)
        if v.size == 1 and el.get("NumNodes") is not None:
            try:
                count = int(el.get("NumNodes"))
            except ValueError:
                count = 0
            if count <= 0:
                raise NiftySimError(
                    f'<ClampedNodes NumNodes="{el.get("NumNodes")[:20]}">: expected a count > 0', f, where
                )
            v = np.arange(v[0], v[0] + count)
        bad = v[(v < 0) | (v >= n_nodes)]
        if bad.size:
            raise NiftySimError(
                f"clamped node {int(bad[0])} out of range; the model has nodes 0..{n_nodes - 1}", f, where
            )
        out.append(v)
    return np.unique(np.concatenate(out))
