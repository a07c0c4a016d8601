"""ModelBuilder: collects a mesh, materials, constraints and loads, validates them, and builds a
static :class:`~pliant.tled.model.Model`. Importers (meshio files, NiftySim XML, scenes) only feed it.

Conventions: SI units (m, kg, s, N, Pa); node coordinates shape (N, 3); tetrahedra shape (M, 4),
positively oriented (det[X1 − X0, X2 − X0, X3 − X0] > 0); DOFs named x, y, z.
"""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass

import numpy as np

from .. import _core
from ..checks import as_real, described, flag, mesh_arrays, real_array, shown, whole_number
from ..errors import (
    DegenerateElementError,
    InputError,
    MaterialError,
    MeshError,
    PliantWarning,
)
from ..materials import Material
from ..materials.membrane import MembraneMaterial
from ..memory import MODEL_BYTES_PER_TET, require_memory
from ..mesh.primitives import triangle_measures
from ..mesh.topology import conformity_problem
from .curves import Constant, LoadCurve
from .geometry import check_geometry, check_material_numbers
from .anp import ANP_STABILIZATION, anp_stabilization
from .smoothing import strain_smoothing

__all__ = ["ModelBuilder"]

_DOFS = {"x": 0, "y": 1, "z": 2}


def _dofs(dofs) -> list[int]:
    if isinstance(dofs, str):
        out = []
        for c in dofs.lower():
            if c not in _DOFS:
                raise InputError(f"dofs = {shown(dofs)}: unknown DOF {shown(c)}; expected letters from 'xyz'")
            out.append(_DOFS[c])
        if not out:
            raise InputError("dofs = '': expected at least one of the letters 'xyz'")
        return sorted(set(out))
    given = np.atleast_1d(np.asarray(dofs, dtype=object))
    numbers = {whole_number(d, "dofs") for d in given} if given.ndim == 1 else set()
    if not numbers or not numbers <= {0, 1, 2}:
        raise InputError(f"dofs = {described(dofs)}: expected 0, 1, 2 or letters from 'xyz'")
    return sorted(numbers)


def _curve(curve, who: str) -> LoadCurve:
    """``curve`` as the load curve it must be (None: the constant 1); InputError naming ``who``
    (the call) otherwise."""
    if curve is None:
        return Constant()
    if not isinstance(curve, LoadCurve):
        raise InputError(
            f"{who}: curve = {described(curve)}; expected a load curve (pliant.Ramp, SmoothRamp, "
            "Step, Hilly, Table) or None for a constant 1"
        )
    return curve


def _check_conforming(X: np.ndarray, T: np.ndarray, src: str) -> None:
    """Refuse tetrahedra (M, 4) that do not make one conforming mesh (topology.conformity_problem:
    an element given twice, three on a face, two on the same side of a face). X: nodes [m] (N, 3)."""
    problem = conformity_problem(X, T)
    if problem is not None:
        raise MeshError(f"{src}: {problem}")


@dataclass
class _ElementSet:
    name: str
    elements: np.ndarray
    material: Material
    density: float


class ModelBuilder:
    """Collects what a model needs (mesh, materials, constraints, loads, tools) and builds the
    static model. Typical use::

        b = ModelBuilder()
        b.add_mesh(nodes, tets)
        b.set_material(NeoHookean(E=3e3, nu=0.45), density=1000.0)
        b.fix(bottom_nodes)
        b.add_force(top_nodes, (0, 0, -0.1), curve=Ramp(1.0))
        model = b.finalize()
    """

    def __init__(self):
        self.nodes = np.zeros((0, 3))
        self.tets = np.zeros((0, 4), dtype=np.int64)
        self.sets: list[_ElementSet] = []
        # Supports: (name, user node ids, DOFs) per fix / prescribe call, for their reactions
        # (Model.support_reactions).
        self.supports: list[tuple[str, np.ndarray, str]] = []
        self.damping = 0.0  # mass-proportional damping α [1/s]
        # Stiffness-proportional (Rayleigh β) damping [s]: a viscous stress β C0 : Ė per element
        # that spares rigid motion; the critical time step shrinks with it (see Model.dt_critical).
        self.stiffness_damping = 0.0
        # Average nodal pressure tetrahedra (T4ANP, NiftySim's element): the pressure of each
        # element is the mean of its nodes' volume-averaged pressures, which much reduces the
        # volumetric locking of linear tets in nearly incompressible tissue. Decoupled materials.
        self.nodal_pressure = False
        # T4ANP stabilization: "shear" (γ = μ/K of each material) or a fraction γ of each element's
        # own pressure mixed back into the averaged one, so that element-level volume modes are
        # resisted (docs/engine.md); 0 is plain T4ANP (NiftySim's).
        self.nodal_pressure_stabilization = ANP_STABILIZATION
        # Where the strain is constant (StrainSmoothing): per element (plain linear tets), or per
        # edge domain, the edge-based smoothed tetrahedron (ES-FEM-T4), far less stiff in bending
        # at about twice the element work (docs/engine.md, "Edge-smoothed strain").
        self.strain_smoothing = _core.StrainSmoothing.Element
        self._cons: dict[tuple[int, int], tuple[float, LoadCurve]] = {}
        self._forces: list[tuple[np.ndarray, np.ndarray, LoadCurve]] = []
        self._pressures: list[tuple[np.ndarray, np.ndarray, LoadCurve]] = []
        self._tractions: list[tuple[np.ndarray, np.ndarray, LoadCurve]] = []  # add_traction
        self._membranes: list[tuple[np.ndarray, MembraneMaterial]] = []  # add_membrane
        self._membrane_clamps: list[np.ndarray | None] = []  # add_membrane's clamped, per call
        self._gravity: tuple[np.ndarray, LoadCurve] | None = None
        self._node_gravity: list[tuple[np.ndarray, np.ndarray, LoadCurve]] = []  # add_gravity
        self.tools: list = []  # rigid tools (pliant.contact)
        self.tool_nodes: list = []  # per tool: node ids it is restricted to, or None (all)
        self.soft_contact = None  # contact between deformable bodies (pliant.contact.SoftContact)
        self.source = "arrays"  # what the mesh came from, for error messages

    # --- mesh -------------------------------------------------------------------------------
    def add_mesh(self, nodes, tets, source: str | None = None) -> np.ndarray:
        """Append nodes [m] (N, 3) and tetrahedra (M, 4) (indices into these nodes, 0-based; M may be
        0, nodes alone, for a sheet of membranes: add_membrane).

        Returns the global indices of the new elements."""
        src = source or self.source
        # M = 0, nodes alone: a sheet of membranes (add_membrane)
        X, T = mesh_arrays(nodes, tets, 4, src, cell="element", empty=True)
        rep = np.sort(T, axis=1)
        dup = np.nonzero(np.any(rep[:, 1:] == rep[:, :-1], axis=1))[0]
        if dup.size:
            k = int(dup[0])
            raise DegenerateElementError(f"{src}: element {k} repeats a node: {T[k].tolist()}", k)
        _check_conforming(X, T, src)
        base = self.nodes.shape[0]
        first = self.tets.shape[0]
        self.nodes = np.vstack([self.nodes, X])
        self.tets = np.vstack([self.tets, T.astype(np.int64) + base])
        self.source = src
        return np.arange(first, self.tets.shape[0])

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_elements(self) -> int:
        return self.tets.shape[0]

    # --- materials --------------------------------------------------------------------------
    def set_material(self, material: Material, density: float, elements=None, name: str | None = None):
        """Assign a material and density [kg/m³] to elements (indices; default: all not yet assigned)."""
        if not isinstance(material, Material):
            raise MaterialError(f"material = {shown(material)}; expected a pliant.materials.Material")
        rho = as_real(density)
        if not math.isfinite(rho) or rho <= 0:
            raise MaterialError(f"density = {shown(density)}; expected a finite value > 0 [kg/m^3]")
        if elements is None:
            taken = np.zeros(self.n_elements, bool)
            for s in self.sets:
                taken[s.elements] = True
            elements = np.nonzero(~taken)[0]
        elements = np.asarray(elements, dtype=np.int64).ravel()
        bad = elements[(elements < 0) | (elements >= self.n_elements)]
        if bad.size:
            raise InputError(
                f"set_material: element index {int(bad[0])} out of range 0..{self.n_elements - 1}"
            )
        self.sets.append(_ElementSet(name or f"set{len(self.sets)}", elements, material, rho))

    # --- constraints and loads --------------------------------------------------------------
    def _node_ids(self, nodes, what: str, empty: bool = True) -> np.ndarray:
        """Node ids as int64: integers, or floats with integral values; anything else (1.5,
        strings, booleans), or no ids at all unless ``empty``, raises InputError naming ``what``."""
        a = np.asarray(nodes)
        if not empty and a.size == 0:  # a selection that missed: the call would do nothing
            raise InputError(f"{what}: no nodes given (an empty selection); expected at least one node id")
        if a.dtype == bool:  # a mask would have been nodes 0 and 1
            raise InputError(
                f"{what}: node ids of type bool (a mask? give np.flatnonzero(mask)); expected integers"
            )
        if not (np.issubdtype(a.dtype, np.integer) or np.issubdtype(a.dtype, np.floating)):
            raise InputError(f"{what}: node ids of type {a.dtype}; expected integers")
        if np.issubdtype(a.dtype, np.floating):
            if not np.all(np.isfinite(a)) or np.any(a != np.round(a)):
                bad = a[~np.isfinite(a) | (a != np.round(a))].ravel()[0]
                raise InputError(f"{what}: node id {float(bad)}; expected integers")
            if a.size and np.abs(a).max() >= 2**62:
                raise InputError(f"{what}: node id {float(np.abs(a).max())}; out of range")
        ids = a.astype(np.int64).ravel()
        if ids.size and (ids.min() < 0 or ids.max() >= self.n_nodes):
            bad = ids[(ids < 0) | (ids >= self.n_nodes)][0]
            raise InputError(f"{what}: node {int(bad)} out of range; expected 0..{self.n_nodes - 1}")
        return ids

    def fix(self, nodes, dofs="xyz", name: str | None = None):
        """Fix the given DOFs of the nodes (zero displacement). Node selections here and in
        prescribe, add_force, add_gravity and add_tool may not be empty (InputError). ``name``
        labels the support's reaction (Model.support_reactions; default "support K")."""
        self._support(name, self._constrain(nodes, 0.0, dofs, Constant(), "fix"), dofs)

    def prescribe(
        self, nodes, displacement, dofs="xyz", curve: LoadCurve | None = None, name: str | None = None
    ):
        """Prescribe displacements [m] on DOFs of nodes, scaled in time by ``curve`` (default 1).

        ``displacement``: a scalar (all DOFs), a vector per DOF in ``dofs`` (len(dofs),), or per
        node (n, len(dofs)). A DOF prescribed twice with different values or curves is an error.
        ``name`` labels the support's reaction, as fix's."""
        self._support(name, self._constrain(nodes, displacement, dofs, curve, "prescribe"), dofs)

    def _support(self, name: str | None, ids: np.ndarray, dofs: str) -> None:
        """Records a support for its reaction; a name given twice is numbered ("base (2)")."""
        label = name or f"support {len(self.supports)}"
        taken = {n for n, _, _ in self.supports}
        k = 2
        while label in taken:
            label, k = f"{name or 'support'} ({k})", k + 1
        self.supports.append((label, ids, "".join("xyz"[d] for d in _dofs(dofs))))

    def _constrain(self, nodes, displacement, dofs, curve: LoadCurve | None, what: str) -> np.ndarray:
        """prescribe (or fix: ``what`` names the call in errors); the node ids."""
        ids = self._node_ids(nodes, what, empty=False)
        ds = _dofs(dofs)
        given = "non-numeric"
        val = real_array(displacement)
        try:
            if val is not None:
                given = f"shape {val.shape}"
                val = np.broadcast_to(val, (ids.size, len(ds))) if val.ndim < 2 else val
        except ValueError:
            val = None
        if val is None or val.shape != (ids.size, len(ds)):
            raise InputError(
                f"prescribe: displacement of {given} for {len(ds)} DOF(s) ({dofs}) of "
                f"{ids.size} node(s); expected a scalar, ({len(ds)},) or "
                f"({ids.size}, {len(ds)}) [m]"
            )
        if not np.all(np.isfinite(val)):
            raise InputError("prescribe: displacement values must be finite")
        curve = _curve(curve, what)
        for i, n in enumerate(ids):
            for j, d in enumerate(ds):
                key = (int(n), d)
                new = (float(val[i, j]), curve)
                old = self._cons.get(key)
                if old is not None and old != new:
                    raise InputError(
                        f"node {int(n)} DOF {'xyz'[d]} is constrained twice: "
                        f"{old[0]:g} m with {shown(old[1])} and {new[0]:g} m with "
                        f"{shown(new[1])}"
                    )
                self._cons[key] = new
        return ids

    def add_force(self, nodes, force, curve: LoadCurve | None = None):
        """Add a force [N] on each node: (3,) for all, or (n, 3) per node; scaled by ``curve``."""
        ids = self._node_ids(nodes, "add_force", empty=False)
        f = real_array(force)
        try:
            f = np.zeros((0, 0)) if f is None else np.broadcast_to(f, (ids.size, 3)) if f.ndim == 1 else f
        except ValueError:
            f = np.zeros((0, 0))
        if f.shape != (ids.size, 3) or not np.all(np.isfinite(f)):
            raise InputError(
                f"add_force: force = {described(force)}; expected finite (3,) or ({ids.size}, 3) [N]"
            )
        self._forces.append((ids, np.array(f), _curve(curve, "add_force")))

    def add_pressure(self, faces, pressure, curve: LoadCurve | None = None, orient: bool = True):
        """Follower pressure [Pa] on surface triangles ``faces`` (F, 3) (user node ids), scaled by
        ``curve``: each step, −p/3 of the triangle's current area vector on each of its nodes.
        ``pressure``: one value or one per face; positive pushes into the body (compression).

        ``orient=True`` (default) takes each face's outward orientation from the mesh (a face must
        then be on its boundary); ``orient=False`` keeps the given winding (normal
        (x1 − x0) × (x2 − x0); positive p pushes against it), as NiftySim does."""
        F = np.asarray(faces)
        if F.ndim != 2 or F.shape[1] != 3 or F.shape[0] == 0 or not np.issubdtype(F.dtype, np.integer):
            raise InputError(
                f"add_pressure: faces of shape {F.shape}, {F.dtype}; expected (F, 3) integer node ids"
            )
        F = self._node_ids(F.ravel(), "add_pressure faces").reshape(-1, 3)
        p = real_array(pressure)
        if p is None:
            p = np.zeros(0)
        elif p.ndim == 0:
            p = np.broadcast_to(p, (F.shape[0],)).copy()
        if p.shape != (F.shape[0],) or not np.all(np.isfinite(p)):
            raise InputError(
                f"add_pressure: pressure = {described(pressure)}; expected a finite "
                f"value or ({F.shape[0]},) [Pa]"
            )
        if orient:
            from ..mesh.topology import boundary_faces

            B, _ = boundary_faces(self.tets)
            index = {tuple(sorted(f)): f for f in B.tolist()}
            out = []
            for i, f in enumerate(F.tolist()):
                b = index.get(tuple(sorted(f)))
                if b is None:
                    raise InputError(
                        f"add_pressure: face {i} (nodes {f}) is not on the mesh "
                        "boundary; pass orient=False to load it as given"
                    )
                out.append(b)
            F = np.array(out, np.int64)
        self._pressures.append((F, p, _curve(curve, "add_pressure")))

    def add_traction(self, faces, traction, curve: LoadCurve | None = None):
        """Surface traction t [Pa] on triangles ``faces`` (F, 3) (user node ids), scaled by
        ``curve``: each step, A t / 3 on each node of a triangle of current area A (force per
        current area, in the fixed direction t; NiftySim's Traction). ``traction``: (3,) for
        every face or (F, 3)."""
        F = np.asarray(faces)
        if F.ndim != 2 or F.shape[1] != 3 or F.shape[0] == 0 or not np.issubdtype(F.dtype, np.integer):
            raise InputError(
                f"add_traction: faces of shape {F.shape}, {F.dtype}; expected (F, 3) integer node ids"
            )
        F = self._node_ids(F.ravel(), "add_traction faces").reshape(-1, 3)
        t = real_array(traction)
        try:
            t = np.zeros((0, 0)) if t is None else np.broadcast_to(t, F.shape).copy() if t.ndim == 1 else t
        except ValueError:
            t = np.zeros((0, 0))
        if t.shape != F.shape or not np.all(np.isfinite(t)):
            raise InputError(
                f"add_traction: traction = {described(traction)}; expected finite (3,) or "
                f"({F.shape[0]}, 3) [Pa]"
            )
        self._tractions.append((F, t, _curve(curve, "add_traction")))

    def add_membrane(self, faces, material: MembraneMaterial, clamped=None):
        """Membrane triangles ``faces`` (F, 3) (user node ids) of ``material``
        (pliant.StVKMembrane or pliant.NeoHookeanMembrane, with its thickness and density): each a
        Total Lagrangian constant-strain triangle that carries in-plane stress (and bending moments
        where the material says ``bending``: docs/engine.md, "Bending"), on the mesh's surface (a
        capsule, a wall), anywhere between its nodes or as a sheet of its own. Its mass ρ h A0 / 3
        adds to each corner's, its wave speed may lower the critical time step (docs/engine.md,
        "Membranes").
        The winding does not matter. Where the material bends (``bending``): ``clamped`` (node ids)
        clamps the boundary edges of these triangles whose two nodes it lists (their slope held,
        NiftySim's <ClampedNodes>); default (None): the edges whose nodes are held in all three
        directions when the model is finalized."""
        if not isinstance(material, MembraneMaterial):
            raise MaterialError(
                f"add_membrane: material {shown(material)}; expected pliant.StVKMembrane or "
                "pliant.NeoHookeanMembrane"
            )
        F = np.asarray(faces)
        if F.ndim != 2 or F.shape[1] != 3 or F.shape[0] == 0 or not np.issubdtype(F.dtype, np.integer):
            raise InputError(
                f"add_membrane: faces of shape {F.shape}, dtype {F.dtype}; expected (F, 3) integer node "
                "ids, F >= 1"
            )
        F = self._node_ids(F.ravel(), "add_membrane faces").reshape(-1, 3)
        area, longest = triangle_measures(self.nodes, F)
        flat = np.nonzero(~(2 * area > 1e-8 * longest**2))[0]
        if flat.size:
            i = int(flat[0])
            raise DegenerateElementError(
                f"{self.source}: membrane {self.n_membranes + i} (nodes {F[i].tolist()}) is "
                f"degenerate: area {area[i]:.3e} m^2 for longest edge {longest[i]:.3e} m; "
                "expected three distinct, non-collinear nodes",
                self.n_membranes + i,
            )
        mass = float(area.max()) * material.thickness * material.density
        if not (math.isfinite(mass) and math.isfinite(material.wave_modulus * material.thickness)):
            raise MaterialError(
                f"add_membrane: {material!r} on triangles of up to {area.max():.3g} m^2: its mass "
                "or stiffness overflows; expected SI units (m, kg/m^3, Pa)"
            )
        if clamped is not None:
            clamped = self._node_ids(np.asarray(clamped).ravel(), "add_membrane clamped")
        self._membranes.append((F, material))
        self._membrane_clamps.append(clamped)

    @property
    def n_membranes(self) -> int:
        """Membrane triangles added so far (add_membrane)."""
        return sum(len(F) for F, _ in self._membranes)

    def set_gravity(self, g=(0.0, 0.0, -9.81), curve: LoadCurve | None = None):
        """Body acceleration g [m/s²] applied to every node as m_a·g, scaled by ``curve``."""
        gv = real_array(g)
        if gv is None or gv.ravel().shape != (3,) or not np.all(np.isfinite(gv)):
            raise InputError(f"gravity = {shown(g)}; expected 3 finite components [m/s^2]")
        gv = gv.ravel()
        self._gravity = (gv, _curve(curve, "set_gravity"))

    def add_gravity(self, g, nodes, curve: LoadCurve | None = None):
        """Body acceleration g [m/s²] on ``nodes`` only (user ids): m_a·g on each, m_a its lumped
        mass, scaled by ``curve``; it adds to set_gravity's and to other add_gravity calls (as
        NiftySim's Gravity constraints, each on its listed nodes, add up). Nodes a cut copies
        (pliant.cutting) keep it."""
        ids = np.unique(self._node_ids(nodes, "add_gravity nodes", empty=False))
        gv = real_array(g)
        if gv is None or gv.ravel().shape != (3,) or not np.all(np.isfinite(gv)):
            raise InputError(f"add_gravity: g = {shown(g)}; expected 3 finite components [m/s^2]")
        gv = gv.ravel()
        self._node_gravity.append((ids, gv, _curve(curve, "add_gravity")))

    def add_tool(self, tool, nodes=None):
        """Add a rigid tool (pliant.contact.Plane, Sphere, Capsule, Cylinder, Box, MeshTool): the
        surface nodes of the body (their free DOFs) are kept out of it, with friction.

        ``nodes``: restrict the tool to these nodes (user ids; e.g. one organ of several, or
        NiftySim's SlvNodes); they take part in contact even if they are not on the surface. Only
        the first 28 tools can be restricted."""
        from ..contact import RigidTool

        if not isinstance(tool, RigidTool):
            raise InputError(f"add_tool: {shown(tool)} is not a pliant.contact tool")
        if nodes is not None:
            if len(self.tools) >= _core.masked_tools:
                raise InputError(
                    f"add_tool {shown(tool.name)}: only the first "
                    f"{_core.masked_tools} tools can be "
                    f"restricted to nodes; this is tool {len(self.tools)}"
                )
            nodes = np.unique(self._node_ids(nodes, f"add_tool {shown(tool.name)} nodes", empty=False))
        self.tools.append(tool)
        self.tool_nodes.append(nodes)
        return tool

    def bodies(self) -> np.ndarray:
        """Body number of each element (M,): the connected parts of the mesh (elements joined by
        shared nodes), numbered in the order of their first element (pliant.contact.soft)."""
        from ..contact.soft import body_labels

        if self.soft_contact is not None and self.soft_contact.labels is not None:
            return self.soft_contact.labels.copy()
        return body_labels(self.tets, self.n_nodes)

    def set_soft_contact(self, friction=0.0, pairs=None, self_contact=False, skin: float | None = None):
        """Contact between deformable bodies: the surface nodes of each body are kept out of the
        surfaces of the bodies it touches, with Coulomb friction ``friction`` (μ or (μs, μk));
        momentum is conserved by each pair (docs/contact.md). ``pairs``: the pairs of body numbers
        (:meth:`bodies`) that touch, or None for every pair of different bodies; ``self_contact``:
        True for every body, or the body numbers that touch themselves (a fold, a grasped flap);
        ``skin`` [m]: the broad phase's Verlet skin (default 0.3 × the median surface edge)."""
        from ..contact.soft import SoftContact

        self.soft_contact = SoftContact.make(friction, pairs, self_contact, skin)
        return self.soft_contact

    # --- topology changes -------------------------------------------------------------------
    def snapshot(self) -> "ModelBuilder":
        """A copy that later calls on this builder do not change (a Model keeps one, to rebuild
        itself after a cut)."""
        b = copy.copy(self)
        b.sets, b._forces, b._pressures = list(self.sets), list(self._forces), list(self._pressures)
        b._node_gravity, b._tractions = list(self._node_gravity), list(self._tractions)
        b._membranes, b._membrane_clamps = list(self._membranes), list(self._membrane_clamps)
        b._cons, b.tools, b.tool_nodes = dict(self._cons), list(self.tools), list(self.tool_nodes)
        b.supports = list(self.supports)
        return b

    def split(self, tets, parent) -> "ModelBuilder":
        """A builder of the same model after node splitting (pliant.cutting): ``tets`` (M, 4) the
        elements over the old nodes and the new ones, ``parent`` (K,) the node each new node
        (numbered n_nodes, n_nodes + 1, …) copies. A copy keeps its parent's constraints, supports
        (their reactions) and node-set memberships (tools', add_gravity's and add_membrane's
        clamped nodes); point forces stay on the parent (their total is unchanged); each pressure,
        traction or membrane face moves to the copies its element now uses."""
        parent = np.asarray(parent, np.int64)
        tets = np.asarray(tets, np.int64)
        b = self.snapshot()
        n0 = self.n_nodes
        b.nodes = np.vstack([self.nodes, self.nodes[parent]])
        b.tets = tets
        copies: dict[int, list[int]] = {}
        for i, n in enumerate(parent.tolist()):
            copies.setdefault(n, []).append(n0 + i)
        for (n, d), v in self._cons.items():
            for c in copies.get(n, ()):
                b._cons[(c, d)] = v
        if self.soft_contact is not None:  # cut pieces keep their body's number
            b.soft_contact = copy.copy(self.soft_contact)
            b.soft_contact.labels = self.bodies()

        def grown(s: np.ndarray) -> np.ndarray:  # a node set with the copies of its nodes
            return np.unique(np.concatenate([s, n0 + np.nonzero(np.isin(parent, s))[0]]))

        b.tool_nodes = [None if s is None else grown(s) for s in self.tool_nodes]
        b.supports = [(name, grown(s), dofs) for name, s, dofs in self.supports]  # copies hold too
        b._node_gravity = [(grown(s), g, c) for s, g, c in self._node_gravity]
        b._membrane_clamps = [None if s is None else grown(s) for s in self._membrane_clamps]
        if self._pressures or self._tractions or self._membranes:
            from ..cutting.split import LOCAL_FACES

            owner = {  # face → its element (a boundary face has one)
                tuple(sorted(f)): e
                for e, t in enumerate(self.tets.tolist())
                for f in np.asarray(t)[LOCAL_FACES].tolist()
            }
            b._pressures = [(self._moved_faces(F, tets, owner), p, c) for F, p, c in self._pressures]
            b._tractions = [(self._moved_faces(F, tets, owner), t, c) for F, t, c in self._tractions]
            b._membranes = [(self._moved_faces(F, tets, owner), m) for F, m in self._membranes]
        return b

    def _moved_faces(self, F: np.ndarray, tets: np.ndarray, owner: dict) -> np.ndarray:
        """Loaded faces F (K, 3) after a split: each boundary face (``owner``: sorted face → its
        element) on the nodes its element ``tets`` now uses, in the same winding; a face that is
        no element's is kept."""
        moved = []
        for f in F.tolist():
            e = owner.get(tuple(sorted(f)))
            if e is None:  # not a face of the mesh (orient=False): keep it
                moved.append(f)
                continue
            local = [int(np.nonzero(self.tets[e] == n)[0][0]) for n in f]  # same winding
            moved.append([int(tets[e, j]) for j in local])
        return np.array(moved, np.int64).reshape(-1, 3)

    def membrane_faces(self) -> np.ndarray:
        """The membranes' triangles (K, 3), node ids, in add_membrane's order."""
        return (
            np.concatenate([F for F, _ in self._membranes]) if self._membranes else np.zeros((0, 3), np.int64)
        )

    def free_membranes(self) -> np.ndarray:
        """Indices of the membranes with a node that no tet uses (a sheet of its own, not a skin on
        a solid). In soft contact, a sheet of them apart from the tets is a body of its own;
        one joined to the tets (a flap) takes no part (pliant.contact.soft.sheets_apart)."""
        from ..mesh.topology import faces_off

        return faces_off(self.membrane_faces(), self.tets)

    def sheet_bodies(self) -> tuple[np.ndarray, np.ndarray]:
        """The membranes of the sheets apart from the tets, which soft contact takes as bodies of
        their own (indices into membrane_faces(), ascending; pliant.contact.soft.sheets_apart), and
        the body number of each: each connected sheet one, numbered after the tets' bodies
        (:meth:`bodies`), in the order of its first membrane."""
        from ..contact.soft import sheet_labels, sheets_apart

        F = self.membrane_faces()
        apart = sheets_apart(F, self.tets, self.n_nodes)[0]
        n_solid = int(self.bodies().max()) + 1 if self.n_elements else 0
        return apart, sheet_labels(F[apart], self.n_nodes, n_solid)

    def _warn_membranes_out_of_contact(self):
        from ..contact.soft import sheets_apart

        if self.soft_contact is None or self.n_elements == 0 or not self._membranes:
            return
        joined = sheets_apart(self.membrane_faces(), self.tets, self.n_nodes)[1]
        if joined.size:
            warnings.warn(
                PliantWarning(
                    f"{self.source}: {joined.size} membrane(s) off the tets but joined to them (first: "
                    f"{int(joined[0])}) take no part in soft contact (a sheet apart from the tets does: "
                    "docs/contact.md): bodies pass through them"
                ),
                stacklevel=3,
            )

    # --- finalize ---------------------------------------------------------------------------
    def finalize(self, dtype="float32", threads: int | None = None, backend: str = "cpu", device: int = 0):
        """Validate everything and build the static Model (engine arrays in a cache-friendly order).

        backend: "cpu" (OpenMP + SIMD), "cuda" (the same engine on an NVIDIA GPU, device-resident)
        or "cuda-emulated" (the CUDA engine run on the host: for tests and debugging); "cuda"
        without a GPU or a CUDA build raises BackendError."""
        from .model import Model, check_backend

        if self.n_elements == 0 and not self._membranes:
            raise MeshError(f"{self.source}: no tetrahedra and no membranes; add a mesh before finalize()")
        self._warn_membranes_out_of_contact()
        require_memory(
            self.n_elements, MODEL_BYTES_PER_TET, f"{self.source}: a model of {self.n_elements:,} tets"
        )
        given = dtype
        try:
            dtype = np.dtype(dtype)
        except (TypeError, ValueError):
            dtype = None
        if dtype not in (np.float32, np.float64):
            raise InputError(f"dtype = {described(given)}; expected 'float32' or 'float64'")
        a = as_real(self.damping)
        if not math.isfinite(a) or a < 0:
            raise InputError(f"damping = {shown(self.damping)}; expected a finite value >= 0 [1/s]")
        flag(self.nodal_pressure, "nodal_pressure")  # bool("no") was True
        anp_stabilization(self.nodal_pressure_stabilization)  # InputError names a wrong value
        beta = as_real(self.stiffness_damping)
        if not math.isfinite(beta) or beta < 0:
            raise InputError(
                f"stiffness_damping = {shown(self.stiffness_damping)}; expected a finite value >= 0 [s]"
            )
        strain_smoothing(self.strain_smoothing)  # InputError names a wrong value
        owner = np.full(self.n_elements, -1, dtype=np.int64)
        for k, s in enumerate(self.sets):
            clash = s.elements[owner[s.elements] >= 0]
            if clash.size:
                raise InputError(
                    f"element {int(clash[0])} is in two element sets "
                    f"({self.sets[owner[clash[0]]].name!r} and {shown(s.name)})"
                )
            owner[s.elements] = k
        if np.any(owner < 0):
            raise MaterialError(
                f"{self.source}: element {int(np.argmax(owner < 0))} has no material; "
                "call set_material() for every element"
            )
        if self.nodal_pressure:
            for s in self.sets:
                if getattr(s.material, "prony", None):
                    raise MaterialError(
                        f"element set {shown(s.name)}: viscoelastic materials and "
                        "average nodal pressure (T4ANP) cannot be combined yet"
                    )
                if not s.material.decoupled:
                    from ..materials.viscoelastic import decoupled_materials

                    raise MaterialError(
                        f"element set {shown(s.name)}: {type(s.material).__name__} has no "
                        "separate volumetric term; average nodal pressure (T4ANP) "
                        f"needs a decoupled material ({', '.join(decoupled_materials())})"
                    )
        X = np.ascontiguousarray(self.nodes)
        T32 = np.ascontiguousarray(self.tets.astype(np.int32))
        vol, alt = _core.tet_geometry(X, T32)
        check_geometry(self.source, X, T32, vol, alt, dtype)
        check_material_numbers(self.source, self.sets, self._membranes, dtype)
        check_backend(backend)
        model = Model(self, owner, dtype, threads, geometry=(vol, alt))
        model._set_default_backend(backend, device)
        return model
