"""NiftySim model import (XML; T4, T4ANP, and H8 split into tetrahedra: niftysim_elements.py):
nodes and elements (listed, or from an <MSHMesh> / <VTKMesh> file: niftysim_geometry.py), element
sets with their materials, membranes (<ShellElements> with their <ShellElementSet>s:
niftysim_membranes.py), Fix / Disp / Force / Gravity / Pressure constraints with their load shapes, the
analytical rigid contacts (ContactPlate, ContactCylinder, ContactUSProbe, with their SlvNodes and
motions), closed ContactSurfaces (fixed or moving, with SlvNodes), SubModels (merged into one model, with
SubModelNodeMergerDistance: niftysim_submodels.py), Output frequency and SystemParams. Anything
else is refused by name (``unsupported`` lists what may be skipped knowingly).

Format: NiftySim user guide v2.4 (Johnsen et al. 2015). Materials: NH = decoupled Neo-Hookean
(μ, K) — pliant's NeoHookean; PY, AB and TI (App. A.1) — Polynomial, ArrudaBoyce and
TransverselyIsotropic; LE = NiftySim's total-Lagrangian "linear elastic" (E, ν), whose S is
λ tr(E) I + 2μ E (tledMaterialLE) — pliant's StVenantKirchhoff. Load shapes use the relative time
t/T of the whole analysis: RAMP, STEP, POLY345, HILLY, RAMPHOLD (ramp over the first 10 %, then
hold; tledConstraint::ComputeAmplitude).
"""

from __future__ import annotations

import contextlib
import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FileError, InputError
from .files import file_problem
from .niftysim_structure import KNOWN_TOP, warn_repeated
from ..mesh.primitives import orient_positive
from ..materials import ArrudaBoyce, NeoHookean, Polynomial, StVenantKirchhoff, TransverselyIsotropic
from ..job import Scene
from ..tled import Constant, Hilly, ModelBuilder, Ramp, SmoothRamp, Step


# NiftySim user guide v2.4, App. A.1: material code → (pliant class, parameters in file order).
_MATERIALS: dict[str, tuple[Any, tuple[str, ...]]] = {
    "NH": (lambda mu, k: NeoHookean(mu=mu, K=k), ("mu", "kappa")),
    "PY": (
        lambda c10, c01, c20, c02, c11, k: Polynomial(c10, c01, c20, c02, c11, K=k),
        ("C10", "C01", "C20", "C02", "C11", "kappa"),
    ),
    "AB": (lambda mu, lm, k: ArrudaBoyce(mu, lm, k), ("mu", "lambda_m", "kappa")),
    # NiftySim's code (tledMaterialTI::ComputeSPKStress, and SPK_TI of its GPU kernels) computes the
    # fibre stress η (Ī4 − 1)(J^-2/3 a⊗a − Ī4/3 C⁻¹): half the derivative of its guide's η/2 (Ī4 − 1)²,
    # which TransverselyIsotropic implements; η/2 makes an imported model behave as in NiftySim
    # (pliant.validate.niftysim_cross: with η as written the two differ by 6.5 % of the displacement).
    "TI": (
        lambda mu, k, eta, a1, a2, a3: TransverselyIsotropic(mu, k, eta / 2, (a1, a2, a3)),
        ("mu", "kappa", "eta", "a1", "a2", "a3"),
    ),
}


class NiftySimError(FileError):
    """A NiftySim file that cannot be imported (malformed, or a feature pliant does not support)."""


def own_text(el) -> str:
    """An element's own text: before its first child and after each (an <ElementSet>'s elements
    follow its <Material>, as in the user guide's examples), not its children's."""
    return " ".join([el.text or "", *(c.tail or "" for c in el)])


def _numbers(el, path, what, dtype=float):
    """The whitespace-separated numbers of an element's own text: finite floats, or integers."""
    if el is None:
        raise NiftySimError(f"<{what}> is missing", str(path), what)
    words = own_text(el).split()
    try:
        a = np.array(words, dtype=np.float64 if dtype is float else dtype)
    except (ValueError, OverflowError):
        bad = next((w for w in words if not _parses(w, dtype)), "?")
        kind = "an integer" if dtype is not float else "a number"
        raise NiftySimError(f"<{what}>: {bad[:40]!r} is not {kind}", str(path), what) from None
    if dtype is float and not np.all(np.isfinite(a)):
        i = int(np.argmax(~np.isfinite(a)))
        raise NiftySimError(
            f"<{what}>: {words[i][:40]!r} (number {i + 1} of {a.size}) is {a[i]}; expected finite numbers",
            str(path),
            what,
        )
    return a


def _parses(word: str, dtype) -> bool:
    try:
        np.array([word], dtype=np.float64 if dtype is float else dtype)
        return True
    except (ValueError, OverflowError):
        return False


def _scalar(text, f: str, key: str, kind=float, low: float | None = None, strict: bool = True):
    """One number from an element's text or an attribute, checked finite and above ``low``
    (strictly, or >= with ``strict=False``); NiftySimError naming the file and key otherwise."""
    try:
        v = kind(str(text).strip())
    except (TypeError, ValueError, OverflowError):
        raise NiftySimError(
            f"<{key}> = {str(text)[:40]!r}: expected {'an integer' if kind is int else 'a number'}", f, key
        ) from None
    if not math.isfinite(v) or (low is not None and (v <= low if strict else v < low)):
        bound = "" if low is None else f" {'>' if strict else '>='} {low:g}"
        raise NiftySimError(f"<{key}> = {v}: expected a finite value{bound}", f, key)
    return v


@contextlib.contextmanager
def _named(f: str, key: str):
    """Builder errors inside become NiftySimErrors naming the file and the XML element."""
    try:
        yield
    except FileError:
        raise
    except InputError as e:
        raise NiftySimError(str(e), f, key) from None


def set_xml_key(root, key: str, value, f: str = "") -> None:
    """Set the text of the element at ``key`` below ``root``: ``'SystemParams.TimeStep'``,
    ``'ElementSet[1].Material.ElasticParams'`` (the n-th element of that tag with ``[n]``, the
    first without) to ``value`` (a number, or a list of numbers written space-separated); a second
    index on the last element, ``'ElementSet.Material.ElasticParams[0][1]'``, sets one number of
    its text. A sweep's parameters on a NiftySim model are set this way."""
    import re

    el = root
    segments = key.split(".")
    for n, seg in enumerate(segments):
        m = re.fullmatch(r"([A-Za-z_][\w-]*)((?:\[\d+\])*)", seg)
        if not m:
            raise NiftySimError(f"segment {seg!r}: expected an element name with optional [index]es", f, key)
        idx = [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
        found = el.findall(m.group(1))
        at = idx[0] if idx else 0
        if at >= len(found):
            raise NiftySimError(
                f"<{el.tag}> has {len(found)} <{m.group(1)}> element(s); expected at least {at + 1}", f, key
            )
        el = found[at]
        if len(idx) > 2 or (len(idx) == 2 and n < len(segments) - 1):
            raise NiftySimError(
                f"segment {seg!r}: a second [index] (a number in the text) "
                "is allowed on the last element only",
                f,
                key,
            )
    words = own_text(el).split()  # its numbers may follow its children (an <ElementSet>'s)
    if len(el) and not words:
        names = ", ".join(sorted({child.tag for child in el}))
        raise NiftySimError(
            f"<{el.tag}> holds elements ({names}), no value of its own; expected the path of a "
            f"value, such as {key}.{el[0].tag}",
            f,
            key,
        )
    if len(idx) == 2:
        if idx[1] >= len(words):
            raise NiftySimError(f"<{el.tag}> holds {len(words)} value(s); [{idx[1]}] is out of range", f, key)
        words[idx[1]] = _word(value, f, key)
        text = " ".join(words)
    elif isinstance(value, (list, tuple)):
        text = " ".join(_word(v, f, key) for v in value)
    else:
        text = _word(value, f, key)
    el.text = text
    for child in el:  # the whole text is before the children now
        child.tail = None


def _word(v, f: str, key: str) -> str:
    """A value as NiftySim reads it: integers as integers, floats to the last bit, true and false
    as 1 and 0, a word as it is (the import names the element where it wanted a number)."""
    if isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    raise NiftySimError(f"value {v!r}: expected a number, a word or a list of numbers", f, key)


def load_niftysim(path, ignore: tuple[str, ...] = (), overrides: dict | None = None) -> Scene:
    """Import a NiftySim XML model. ``ignore`` names unsupported features to skip with a warning
    (e.g. 'DoDeformableCollision'); any other unsupported feature is an error naming it.
    ``overrides`` maps element paths to values set before import (see :func:`set_xml_key`)."""
    path = Path(path)
    problem = file_problem(path)
    if problem:
        raise NiftySimError(f"{problem}; expected a NiftySim XML model file", str(path))
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as e:
        raise NiftySimError(f"not a readable XML file ({e})", str(path)) from None
    f = str(path)
    for key, value in (overrides or {}).items():
        set_xml_key(root, key, value, f)
    if root.tag != "Model":
        raise NiftySimError(f"root element <{root.tag}>; expected <Model>", f)
    warnings: list[str] = []

    def unsupported(name: str, why: str):
        if name in ignore:
            warnings.append(f"{f}: ignored unsupported NiftySim feature {name} ({why})")
            return
        raise NiftySimError(
            f"unsupported NiftySim feature {name}: {why}; pass --ignore {name} to skip it knowingly", f, name
        )

    warn_repeated(root, f, warnings)
    # The model's membranes or its sub-models' (which the merge below reads unless skipped).
    skip_membranes = "ShellElements" in ignore and root.find(".//ShellElements") is not None
    root = _flatten(root, f, not skip_membranes)
    for child in root:
        if child.tag not in KNOWN_TOP:
            unsupported(child.tag, "not implemented in pliant")
    if skip_membranes:
        warnings.append(f"{f}: ignored ShellElements as asked (--ignore ShellElements): the solid runs alone")

    from .niftysim_elements import as_tets, h8_as_t4anp
    from .niftysim_system import system_params

    X, E, etype = _mesh(root, f)
    T, owner = as_tets(X, E, f, "Elements")  # owner: the model's element of each tet
    T = _reoriented(X, T, f, warnings)
    dt, total, damping, default_rho, collide = system_params(root, f, unsupported, warnings, etype)
    b = ModelBuilder()
    with _named(f, "Elements"):
        b.add_mesh(X, T, source=f)
    _submeshes(root, T, owner, len(E), len(X), f, warnings)
    b.damping = damping
    b.nodal_pressure_stabilization = 0.0  # NiftySim's T4ANP: the plain average
    _element_sets(root, b, owner, len(E), default_rho, f, unsupported)
    shells_as_membranes = False
    if not skip_membranes:
        from .niftysim_membranes import add_membranes

        shells_as_membranes = add_membranes(root, b, T, f, unsupported, warnings)
    b.nodal_pressure = etype == "T4ANP"  # average nodal pressure tetrahedra
    if etype == "H8":
        b.nodal_pressure = h8_as_t4anp(b, len(E), len(T), f, warnings)
    shapes = {
        "RAMP": lambda: Ramp(total),
        "STEP": lambda: Step(0.0),
        "POLY345": lambda: SmoothRamp(total),
        "HILLY": lambda: Hilly(total),
        "RAMPHOLD": lambda: Ramp(0.1 * total),
    }  # NiftySim: ramp over 10 % of T, then hold
    for k, c in enumerate(root.findall("Constraint")):
        key = f"Constraint[{k}]"
        with _named(f, key):
            _constraint(c, b, T, shapes, f, key, unsupported)

    with _named(f, "ContactPlate/ContactCylinder/ContactUSProbe"):
        _rigid_contacts(root, b, total, f, unsupported, warnings)
    with _named(f, "ContactSurface"):
        _rigid_surfaces(root, b, path, total, f, unsupported)
    deformable, self_collide, mu = collide
    if deformable or self_collide:  # frictionless unless <DeformableFrictionCoefficient> says
        from ..contact.soft import sheets_apart

        free = b.free_membranes()
        joined = sheets_apart(b.membrane_faces(), b.tets, b.n_nodes)[1] if free.size else free
        if joined.size:  # NiftySim's contact holds them (tledDeformableMembraneContactSurface)
            unsupported(
                "MembraneContact",
                f"{joined.size} membrane(s) off the solid's surface but joined to it would take part in "
                "NiftySim's deformable contact; pliant's soft contact takes sheets of membranes apart from "
                "the tets, not joined to them, so bodies would pass through these; skipping it runs the "
                "model with those membranes out of contact",
            )
        b.set_soft_contact(friction=mu, pairs=None if deformable else [], self_contact=self_collide)
    elif mu:
        warnings.append(
            f"{f}: DeformableFrictionCoefficient ignored: the model turns on no deformable contact "
            "(DoDeformableCollision, DoSelfCollision)"
        )

    out_every, variables = None, []
    for o in root.findall("Output"):
        out_every = _scalar(o.get("Freq"), f, "Output Freq", int, 1, False)
        variables += [(v.text or "").strip() for v in o.findall("Variable")]
    scene = Scene(
        f,
        b,
        duration=total,
        dt=dt,
        dtype="float32",
        output_every=out_every,
        frames=20,
        title=path.stem,
        warnings=warnings,
    )
    scene.meta["mesh_source"] = f
    written = [v for v in ("U", "F") if v in variables]  # NiftySim's U.txt, F.txt (runner.py)
    if written:
        scene.meta["niftysim_outputs"] = written
    other = sorted(set(variables) - {"U", "F"})
    if other:
        warnings.append(
            f"{f}: <Output> Variable {', '.join(other)} not written as NiftySim's text files (pliant writes "
            "U.txt and F.txt; each frame holds stresses and strains: fields cauchy, green_strain)"
        )
    # NiftySim's step suits its own elements; pliant's in their place may need a smaller one: the
    # tets of a split hexahedral mesh, the constant-strain membranes of its shell triangles (NiftySim
    # runs membrane_stretch_shell_irregular.xml's shells at 1 ms, pliant's membranes need 0.86).
    reasons = ["H8 elements split into tetrahedra"] if etype == "H8" else []
    if shells_as_membranes:
        reasons.append("shell triangles run as constant-strain membranes")
    if reasons:
        scene.meta["dt_divides"] = " and the ".join(reasons)
    return scene


def _reoriented(X: np.ndarray, T: np.ndarray, f: str, warnings: list[str]) -> np.ndarray:
    """The tetrahedra (M, 4) with those of negative orientation turned over (orient_positive),
    and a warning that says how many. NiftySim takes each element's volume as |det J| / 6 and its
    shape-function derivatives from J⁻¹ (tledElementT4::ComputeDhDx), so either orientation is the
    same element there; pliant's elements are positively oriented. Elements that overlap (two on
    the same side of a face) are still refused, by ModelBuilder.add_mesh."""
    if not (T.size and T.min() >= 0 and T.max() < len(X)):  # bad indices: add_mesh names them
        return T
    turned = orient_positive(X, T)
    neg = np.nonzero(np.any(turned != T, axis=1))[0]
    if neg.size:
        warnings.append(
            f"{f}: {neg.size} of {len(T)} element(s) given with negative orientation (first: element "
            f"{int(neg[0])}) turned over (nodes 3 and 4 swapped), as NiftySim takes |det J|"
        )
    return turned


def _flatten(root, f: str, membranes: bool):
    """The model with its <SubModel>s merged into one (niftysim_submodels.py), their membranes
    too unless ``membranes`` is False."""
    from .niftysim_submodels import flatten_submodels

    return flatten_submodels(root, f, membranes)


def _mesh(root, f: str) -> tuple[np.ndarray, np.ndarray, str]:
    """<Nodes> (N, 3) and <Elements> (M, 4) with their counts checked, or the mesh of an <MSHMesh>
    or <VTKMesh> file (niftysim_geometry.py); the element type."""
    from .niftysim_elements import ELEMENT_NODES
    from .niftysim_geometry import MESH_FILE_TAGS, mesh_file

    nodes_el = root.find("Nodes")
    elems_el = root.find("Elements")
    files = [el for el in root if el.tag in MESH_FILE_TAGS]
    if files:
        if len(files) > 1 or nodes_el is not None or elems_el is not None:
            raise NiftySimError(
                "more than one mesh: expected one of <MSHMesh>, <VTKMesh> or <Nodes> with <Elements>",
                f,
                files[-1].tag,
            )
        return mesh_file(files[0], f)
    if nodes_el is None or elems_el is None:
        raise NiftySimError("missing <Nodes> or <Elements> (or a <MSHMesh> or <VTKMesh> file)", f)
    if nodes_el.get("DOF", "3") != "3":
        raise NiftySimError(f"<Nodes DOF={nodes_el.get('DOF')!r}>: only 3 DOF per node", f, "Nodes")
    X = _numbers(nodes_el, f, "Nodes")
    if X.size % 3:
        raise NiftySimError(f"<Nodes>: {X.size} coordinates, not a multiple of 3", f, "Nodes")
    X = X.reshape(-1, 3)
    if "NumNodes" in nodes_el.attrib and _scalar(
        nodes_el.get("NumNodes"), f, "Nodes NumNodes", int, 0
    ) != len(X):
        raise NiftySimError(
            f"<Nodes NumNodes={nodes_el.get('NumNodes')}> but {len(X)} nodes listed", f, "Nodes"
        )
    etype = elems_el.get("Type")
    if etype not in ELEMENT_NODES:  # other connectivities cannot be read: not ignorable
        raise NiftySimError(
            f"unsupported NiftySim feature Elements Type={etype}: pliant imports T4, T4ANP and H8 "
            "(split into tetrahedra)",
            f,
            "Elements",
        )
    n = ELEMENT_NODES[etype]
    T = _numbers(elems_el, f, "Elements", np.int64)
    if T.size % n:
        raise NiftySimError(
            f"<Elements Type={etype}>: {T.size} indices, not a multiple of {n}", f, "Elements"
        )
    T = T.reshape(-1, n)
    M = len(T)
    if (
        "NumEls" in elems_el.attrib
        and _scalar(elems_el.get("NumEls"), f, "Elements NumEls", int, 0, False) != M
    ):
        raise NiftySimError(
            f"<Elements NumEls={elems_el.get('NumEls')}> but {M} elements listed", f, "Elements"
        )

    return X, T, etype


def _submeshes(
    root, T: np.ndarray, owner: np.ndarray, M: int, n_nodes: int, f: str, warnings: list[str]
) -> None:
    """<SubMesh>start end</SubMesh>: element ranges [start, end) naming the meshes of a model (as
    ball_ball.xml's two balls; elements as the model numbers them, the tets T coming from the
    elements ``owner``). Checked (integers, 0 <= start < end <= element count, no overlap);
    pliant takes the bodies from the mesh's connectivity (body_labels), so a range that cuts
    through a connected body leaves a warning."""
    ranges: list[tuple[int, int, str]] = []
    for k, sm in enumerate(root.findall("SubMesh")):
        key = f"SubMesh[{k}]"
        words = (sm.text or "").split()
        if len(words) != 2 or not all(_parses(w, np.int64) for w in words):
            raise NiftySimError(
                f"<SubMesh> = {(sm.text or '').strip()[:40]!r}: expected two integers, start end", f, key
            )
        a, e = int(words[0]), int(words[1])
        if not 0 <= a < e <= M:
            raise NiftySimError(
                f"<SubMesh> = {a} {e}: expected 0 <= start < end <= {M} (the element count)", f, key
            )
        for b0, b1, other in ranges:
            if a < b1 and b0 < e:
                raise NiftySimError(f"<SubMesh> = {a} {e} overlaps {other} ({b0} {b1})", f, key)
        ranges.append((a, e, key))
    if ranges:
        from ..contact.soft import body_labels

        labels = np.zeros(M, np.int64)
        labels[owner] = body_labels(T, n_nodes)  # an element's tets are one body
        whole = np.bincount(labels)
        for a, e, key in ranges:
            part = np.bincount(labels[a:e], minlength=whole.size)
            if np.any((part > 0) & (part < whole)):
                warnings.append(
                    f"{f}: {key} (elements {a} to {e - 1}) holds part of a body connected beyond it; "
                    "pliant's bodies are the mesh's connected parts"
                )


def element_set(es, M: int, f: str, key: str) -> np.ndarray:
    """The elements of an <ElementSet> among M: its list, Size="all", or the shorthand of Size
    consecutive elements from the first listed (user guide v2.4 §3.3; tledModel::GetElSet)."""
    size = es.get("Size", "")
    listed = _numbers(es, f, key, np.int64)
    if size == "all":
        return np.arange(M)
    try:
        n = int(size)
    except ValueError:
        raise NiftySimError(f"<ElementSet Size={size[:40]!r}>: expected a count or 'all'", f, key) from None
    if not 0 <= n <= M:
        raise NiftySimError(f"<ElementSet Size={n}>: expected 0 to {M} (the element count) or 'all'", f, key)
    if listed.size == n:
        elems = listed
    elif listed.size <= 1:  # shorthand: N consecutive elements from the first listed (or 0)
        first = int(listed[0]) if listed.size else 0
        elems = np.arange(first, first + n)
    else:
        raise NiftySimError(f"<ElementSet Size={n}> lists {listed.size} elements", f, key)
    bad = elems[(elems < 0) | (elems >= M)]
    if bad.size:
        raise NiftySimError(f"element index {int(bad[0])} out of range 0..{M - 1}", f, key)
    return elems


def facets_facing(X: np.ndarray, B: np.ndarray, normal: np.ndarray, angle: float) -> np.ndarray:
    """The facets B (F, 3) of nodes X whose normal is within ``angle`` degrees of ``normal``
    (NiftySim's SpecType="NORMAL" with its ToleranceAngle)."""
    area = np.cross(X[B[:, 1]] - X[B[:, 0]], X[B[:, 2]] - X[B[:, 0]])
    cosang = area @ (normal / np.linalg.norm(normal)) / np.linalg.norm(area, axis=1)
    return B[cosang >= np.cos(np.radians(angle)) - 1e-12]


def elastic_params(ep, f: str, key: str) -> np.ndarray:
    """The numbers of an <ElasticParams> element (``key`` names it), as many as its NumParams
    declares where it does."""
    vals = _numbers(ep, f, key)
    declared = ep.get("NumParams")
    if declared is not None and declared.strip() != str(vals.size):
        raise NiftySimError(
            f'<ElasticParams NumParams="{declared[:20]}"> holds {vals.size} value(s); expected as many as '
            "it declares",
            f,
            key,
        )
    return vals


def _element_sets(root, b: ModelBuilder, owner: np.ndarray, M: int, default_rho, f: str, unsupported) -> None:
    """<ElementSet>s: a material and a density on listed (or all) of the model's M elements (the
    tets of element e are those whose ``owner`` is e)."""
    covered = np.zeros(M, bool)
    for k, es in enumerate(root.findall("ElementSet")):
        key = f"ElementSet[{k}]"
        elems = element_set(es, M, f, key)
        covered[elems] = True
        m = es.find("Material")
        if m is None:
            raise NiftySimError("<ElementSet> without <Material>", f, key)
        mtype = m.get("Type")
        ep = m.find("ElasticParams")
        vals = elastic_params(ep, f, f"{key}/ElasticParams") if ep is not None else np.zeros(0)
        rho_el = m.find("Density")
        rho = (
            _scalar(rho_el.text, f, f"{key}/Material/Density", float, 0.0)
            if rho_el is not None
            else default_rho
        )
        if rho is None:
            raise NiftySimError("no density: give <Density> in the material or SystemParams", f, key)
        with _named(f, key):
            if mtype == "LE":
                if vals.size != 2:
                    raise NiftySimError(f"LE takes 2 parameters (E, nu); got {vals.size}", f, key)
                material = StVenantKirchhoff(E=vals[0], nu=vals[1])
            elif mtype in _MATERIALS or mtype in ("NHV", "TIV"):
                cls, names = _MATERIALS[mtype[:-1] if mtype in ("NHV", "TIV") else mtype]
                if vals.size != len(names):
                    raise NiftySimError(
                        f"{mtype} takes {len(names)} parameters ({', '.join(names)}); got {vals.size}", f, key
                    )
                material = cls(*vals)
                if mtype in ("NHV", "TIV"):
                    material = _visco(m, material, f, key)
            else:
                unsupported(f"Material Type={mtype}", "pliant imports NH, LE, PY, AB, TI, NHV and TIV")
                raise NiftySimError(  # ignored: a run has no material to give those elements
                    f"ignoring <Material Type={mtype!r}> leaves the set's {elems.size} element(s) without "
                    "a material; expected NH, LE, PY, AB, TI, NHV or TIV for them",
                    f,
                    f"{key}/Material",
                )
            tets = elems if M == len(owner) else np.nonzero(np.isin(owner, elems))[0]
            b.set_material(material, rho, elements=tets, name=key)
    if not covered.all():
        e = int(np.argmin(covered))
        raise NiftySimError(f"element {e} is in no <ElementSet>; expected every element in one (§3.4.1)", f)


def _constraint(c, b: ModelBuilder, T, shapes: dict, f: str, key: str, unsupported) -> None:
    """One <Constraint>: Pressure, Fix, Disp, Force or Gravity."""
    ctype = c.get("Type")
    if ctype in ("Pressure", "Traction"):
        from .niftysim_geometry import surface_load

        surface_load(c, b, T, shapes, f, key, unsupported)
        return
    if c.get("SpecType", "NODES") not in ("NODES", "NORMAL"):
        unsupported(f"Constraint SpecType={c.get('SpecType')}", "pliant imports NODES and NORMAL")
        return
    if ctype not in ("Fix", "Disp", "Force", "Gravity"):
        unsupported(
            f"Constraint Type={ctype}", "pliant imports Fix, Disp, Force, Gravity, Pressure and Traction"
        )
        return
    dof = c.get("DOF", "all")
    dofs = "xyz" if dof == "all" else {"0": "x", "1": "y", "2": "z"}.get(dof)
    if dofs is None:
        raise NiftySimError(f"DOF={dof!r}: expected 0, 1, 2 or all", f, key)
    curve = Constant()
    if ctype != "Fix":
        shape = c.get("LoadShape")
        if shape not in shapes:
            unsupported(f"LoadShape={shape}", "pliant imports RAMP, STEP, POLY345, HILLY and RAMPHOLD")
            return
        curve = shapes[shape]()
    if ctype == "Gravity":
        mag_el, dir_el = c.find("AccelerationMagnitude"), c.find("AccelerationDirection")
        if mag_el is None or dir_el is None:
            raise NiftySimError("Gravity needs <AccelerationMagnitude> and <AccelerationDirection>", f, key)
        g = _scalar(mag_el.text, f, f"{key}/AccelerationMagnitude")
        d = _numbers(dir_el, f, f"{key}/AccelerationDirection")
        if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0:
            raise NiftySimError(
                f"<AccelerationDirection> {d.tolist()}: expected 3 finite numbers, not all zero", f, key
            )
    from .niftysim_geometry import constraint_nodes

    ids = constraint_nodes(c, b.nodes, T, f, key)
    if ctype == "Gravity":  # on its listed nodes only (tledGravityConstraint); several add up
        b.add_gravity(g * d / np.linalg.norm(d), ids, curve)
        return
    if ctype == "Fix":
        b.fix(ids, dofs, name=key)
        return
    mag = c.find("Magnitudes")
    if mag is None:
        raise NiftySimError(f"{ctype} needs <Magnitudes>", f, key)
    mtype = mag.get("Type", "UNIFORM")
    if mtype not in ("UNIFORM", "DIFFORM"):
        unsupported(f"Magnitudes Type={mtype}", "pliant imports UNIFORM and DIFFORM")
        return
    vals = _numbers(mag, f, f"{key}/Magnitudes")
    if mtype == "UNIFORM" and vals.size == 1:
        v = np.full(ids.size, vals[0])
    elif mtype == "DIFFORM" and vals.size == ids.size:
        v = vals
    else:
        raise NiftySimError(f"Magnitudes {mtype}: {vals.size} values for {ids.size} nodes", f, key)
    ndof = len(dofs)
    if ctype == "Disp":
        b.prescribe(ids, np.repeat(v[:, None], ndof, axis=1), dofs, curve, name=key)
    else:
        force = np.zeros((ids.size, 3))
        for d in dofs:
            force[:, "xyz".index(d)] = v
        b.add_force(ids, force, curve)


def _vector(el, tag, f, key, n=3):
    c = el.find(tag)
    if c is None:
        raise NiftySimError(f"<{el.tag}> lacks <{tag}>", f, key)
    v = _numbers(c, f, f"{key}/{tag}")
    if v.size != n or not np.all(np.isfinite(v)):
        raise NiftySimError(f"<{tag}>: expected {n} numbers, got {v.size}", f, f"{key}/{tag}")
    return v if n > 1 else float(v[0])


def _rigid_contacts(root, b: ModelBuilder, total: float, f: str, unsupported, warnings) -> None:
    """NiftySim's analytical rigid contacts (user guide v2.4 §3.9.1) as pliant tools, frictionless
    like NiftySim's. Each moves by its displacement d times the POLY345 profile of the relative
    time, s = 10 tR³ − 15 tR⁴ + 6 tR⁵ (user guide eq. 1), sampled as 100 keyframes (linear
    interpolation between them: within 7e-5 |d|). SlvNodes restrict the tool to those nodes.

    ContactPlate (corners a, b, c; normal (b − a) × (c − a)) → a Box whose top face is the
    rectangle and whose depth is its longer side. ContactCylinder (Origin at one end, Axis,
    Radius, Length) → a flat-ended Cylinder; NiftySim ignores nodes beyond the ends, pliant pushes
    them out through the end faces. ContactUSProbe (a cylinder with a hemispherical tip at
    Origin + Length·Axis) → a Capsule, which is rounded at the back end too."""
    from ..contact import Box, Capsule, Cylinder, RigidTool, quat_align_z, quat_from_matrix

    s_of = lambda tr: tr**3 * (10 - 15 * tr + 6 * tr**2)  # noqa: E731
    times = np.linspace(0.0, total, 101)
    for tag in ("ContactPlate", "ContactCylinder", "ContactUSProbe"):
        for k, el in enumerate(root.findall(tag)):
            key = f"{tag}[{k}]"
            if tag == "ContactPlate":
                a, bb, c = (_vector(el, t, f, key) for t in ("a", "b", "c"))
                ab, ac = bb - a, c - a
                L1, L2 = np.linalg.norm(ab), np.linalg.norm(ac)
                if not (L1 > 0 and L2 > 0) or abs(ab @ ac) > 1e-6 * L1 * L2:
                    raise NiftySimError(
                        "ContactPlate: corners a, b, c must span a rectangle (b − a ⟂ c − a, both non-zero)",
                        f,
                        key,
                    )
                n = np.cross(ab, ac) / (L1 * L2)
                depth = max(L1, L2)
                R = np.column_stack([ab / L1, ac / L2, n])
                start = a + (ab + ac) / 2 - n * depth / 2
                tool: RigidTool = Box((L1 / 2, L2 / 2, depth / 2), name=f"niftysim {key}")
                rot = quat_from_matrix(R)
                disp = _vector(el, "Disp", f, key) if el.find("Disp") is not None else np.zeros(3)
            else:
                origin, axis = _vector(el, "Origin", f, key), _vector(el, "Axis", f, key)
                radius, length = _vector(el, "Radius", f, key, 1), _vector(el, "Length", f, key, 1)
                na = np.linalg.norm(axis)
                if not na > 0:
                    raise NiftySimError(f"{tag}: <Axis> must be non-zero", f, key)
                axis = axis / na
                if el.find("RadChange") is not None and _vector(el, "RadChange", f, key, 1) != 0:
                    unsupported(f"{tag}/RadChange", "pliant's tools keep their radius")
                try:
                    cls = Cylinder if tag == "ContactCylinder" else Capsule
                    tool = cls(radius, length, name=f"niftysim {key}")
                except InputError as e:
                    raise NiftySimError(str(e), f, key) from None
                start = origin + axis * length / 2
                rot = quat_align_z(axis)
                disp = _vector(el, "OrigDisp", f, key) if el.find("OrigDisp") is not None else np.zeros(3)
            if np.any(disp != 0):
                for t in times:
                    tool.at(float(t), start + s_of(t / total) * disp, rot)
            else:
                tool.at(0.0, start, rot)
            slaves = el.find("SlvNodes")
            nodes = None
            if slaves is not None:
                nodes = _numbers(slaves, f, f"{key}/SlvNodes", np.int64)
                if nodes.size and (nodes.min() < 0 or nodes.max() >= b.n_nodes):
                    raise NiftySimError(
                        f"SlvNodes: node index out of range 0..{b.n_nodes - 1}", f, f"{key}/SlvNodes"
                    )
            try:
                b.add_tool(tool, nodes=nodes)
            except InputError as e:
                raise NiftySimError(str(e), f, key) from None


def _rigid_surfaces(root, b: ModelBuilder, path: Path, total: float, f: str, unsupported) -> None:
    """<ContactSurface> (user guide v2.4 §3.9.2): a rigid triangle surface, inline (<Nodes>,
    <Elements Type="T3">) or from <VTKSurface Type="T3"> (a path relative to the model file), as a
    pliant MeshTool (signed-distance grid: the surface must be closed). Frictionless. With
    <Motion>s it moves (_surface_motion); with <SlvNodes> it meets only those nodes."""
    from ..contact import MeshTool
    from ..mesh import check_surface, read_surface

    for k, el in enumerate(root.findall("ContactSurface")):
        key = f"ContactSurface[{k}]"
        for child in el:
            if child.tag not in ("Nodes", "Elements", "VTKSurface", "Motion", "SlvNodes"):
                unsupported(
                    f"ContactSurface/{child.tag}", "pliant imports rigid surfaces, their Motion and SlvNodes"
                )
                return
        vtk = el.find("VTKSurface")
        try:
            if vtk is not None:
                p = Path((vtk.text or "").strip())
                V, F = read_surface(p if p.is_absolute() else path.parent / p)
            else:
                ne, ee = el.find("Nodes"), el.find("Elements")
                if ne is None or ee is None:
                    raise NiftySimError("ContactSurface needs <VTKSurface> or <Nodes> and <Elements>", f, key)
                V = _numbers(ne, f, f"{key}/Nodes").reshape(-1, 3)
                F = _numbers(ee, f, f"{key}/Elements", np.int64).reshape(-1, 3)
        except NiftySimError:
            raise
        except (InputError, ValueError) as e:
            raise NiftySimError(f"ContactSurface: {e}", f, key) from None
        if not check_surface(V, F).watertight:
            raise NiftySimError(
                "ContactSurface: the surface is not closed; pliant's mesh tools "
                "keep nodes out of a closed volume",
                f,
                key,
            )
        tool = MeshTool(V, F, name=f"niftysim {key}")
        for t, position, q in _surface_motion(el, total, f, key):
            tool.at(t, position, q)
        slv = el.find("SlvNodes")
        with _named(f, f"{key}/SlvNodes"):
            b.add_tool(tool, nodes=None if slv is None else _numbers(slv, f, f"{key}/SlvNodes", np.int64))


def _surface_motion(el, total: float, f: str, key: str) -> list:
    """A moving ContactSurface's keyframes (time [s], position [m], quaternion): NiftySim
    (tledMovingRigidContactSurface) moves its vertices y to R(s)(y − c) + c + s·t at the fraction
    s = time/TotalTime of the analysis, with <Motion Type="Translation"> t (3 numbers [m]) and
    <Motion Type="Rotation"> the total angles (αx, αy, αz) [rad] then the centre c [m], R(s) =
    Rz(s αz) Ry(s αy) Rx(s αx). A pliant tool's pose maps y to R y + p: p = c + s·t − R c; sampled
    at 101 keyframes (nlerp between them: within 1e-5 rad of the path for total angles up to 1
    rad). No <Motion>: no keyframes (a fixed surface)."""
    from ..contact import quat_from_matrix

    t_total, angles, centre = np.zeros(3), np.zeros(3), np.zeros(3)
    motions = el.findall("Motion")
    for m in motions:
        kind = m.get("Type")
        v = _numbers(m, f, f"{key}/Motion")
        if kind == "Translation" and v.size == 3:
            t_total = v
        elif kind == "Rotation" and v.size == 6:
            angles, centre = v[:3], v[3:]
        else:
            raise NiftySimError(
                f'<Motion Type="{kind}"> with {v.size} numbers; expected Type="Translation" (tx ty tz) '
                'or Type="Rotation" (three angles [rad], then the centre)',
                f,
                f"{key}/Motion",
            )
    if not motions:
        return []

    def rotation(s: float) -> np.ndarray:
        R = np.eye(3)
        for axis in range(3):  # x, then y, then z (tledMovingRigidContactSurface.tpp)
            a = s * angles[axis]
            c, sn = math.cos(a), math.sin(a)
            i, j = (axis + 1) % 3, (axis + 2) % 3
            G = np.eye(3)
            G[i, i], G[i, j], G[j, i], G[j, j] = c, -sn, sn, c
            R = G @ R
        return R

    keys = []
    for s in np.linspace(0.0, 1.0, 101 if np.any(angles) else 2):
        R = rotation(s)
        keys.append((s * total, centre + s * t_total - R @ centre, quat_from_matrix(R)))
    return keys


def _visco(m, material, f: str, key: str):
    """<ViscoParams NumIsoTerms NumVolTerms>: α1 τ1 α2 τ2 … for the isochoric terms, then the
    volumetric ones (user guide v2.4, §3.4.4) → pliant.Viscoelastic."""
    from ..materials import Viscoelastic

    vp = m.find("ViscoParams")
    if vp is None:
        raise NiftySimError(f"{m.get('Type')} needs <ViscoParams>", f, key)
    try:
        ni, nv = int(vp.get("NumIsoTerms", "0")), int(vp.get("NumVolTerms", "0"))
    except ValueError:
        raise NiftySimError("<ViscoParams NumIsoTerms/NumVolTerms>: expected integers", f, key) from None
    v = _numbers(vp, f, f"{key}/ViscoParams")
    if v.size != 2 * (ni + nv):
        raise NiftySimError(
            f"<ViscoParams>: {v.size} values for {ni} + {nv} terms (expected {2 * (ni + nv)})", f, key
        )
    pairs = v.reshape(-1, 2).tolist()
    return Viscoelastic(material, iso=pairs[:ni], vol=pairs[ni:])
