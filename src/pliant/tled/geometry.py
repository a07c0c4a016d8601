"""The checks ModelBuilder.finalize runs on the element geometry (finite, within the engine's number
range, not flat, positively oriented: README, "Conventions"), on the materials' numbers (each one
the engine's dtype holds) and on what the first step would move farther than an element."""

from __future__ import annotations

import numpy as np

from ..errors import DegenerateElementError, InvertedElementError, MaterialError, MeshError

# An element is flat when its volume is below this fraction of its longest edge cubed.
FLAT = 1e-8
# Room left at each end of the floating-point range for the engine's products of a volume: forces
# V0·F·S·∇N pass through V0·S (moduli up to 1e12 Pa), masses ρ·V0, and small strains' stresses
# must not fall into subnormal numbers.
ROOM_ABOVE, ROOM_BELOW = 1e12, 1e6


def volume_range(dtype) -> tuple[float, float]:
    """The element volumes [m^3] whose products the engine keeps finite and normal in ``dtype``
    (float32: 1.2e-32 to 3.4e26; float64: 2.2e-302 to 1.8e296)."""
    f = np.finfo(dtype)
    return float(f.tiny) * ROOM_BELOW, float(f.max) / ROOM_ABOVE


def check_geometry(
    source: str, X: np.ndarray, T: np.ndarray, vol: np.ndarray, alt: np.ndarray, dtype
) -> None:
    """Raise the MeshError that names the first element of tets T (M, 4) on nodes X [m] (N, 3)
    whose volume vol [m^3] (M,) or smallest altitude alt [m] (M,) is not finite, whose volume the
    engine's ``dtype`` cannot hold with its products, or that is flat (DegenerateElementError) or
    inverted (InvertedElementError)."""
    bad = np.nonzero(~(np.isfinite(vol) & np.isfinite(alt)))[0]
    if bad.size:
        raise MeshError(
            f"{source}: element {int(bad[0])} has a non-finite volume or altitude: coordinates up to "
            f"{float(np.abs(X).max()):.3g} m overflow (SI metres expected; scale the mesh)"
        )
    edges = X[T[:, [1, 2, 3, 2, 3, 3]]] - X[T[:, [0, 0, 0, 1, 1, 2]]]
    lmax = np.sqrt((edges**2).sum(-1)).max(axis=1, initial=0.0)
    cube = lmax**3  # an element whose four nodes coincide has no edge: 0, flagged below
    rel = np.divide(vol, cube, out=np.zeros_like(vol), where=cube > 0)
    flat = np.abs(rel) < FLAT
    lo, hi = volume_range(dtype)
    size = np.abs(vol)
    out = np.nonzero(((size < lo) & ~flat) | (size > hi))[0]
    if out.size:
        e = int(out[0])
        raise MeshError(
            f"{source}: element {e} has volume {size[e]:.3g} m^3 (longest edge {lmax[e]:.3g} m), "
            f"beyond what {np.dtype(dtype).name} holds with the engine's products ({lo:.2g} to "
            f"{hi:.2g} m^3); expected SI metres (scale the mesh)"
            + ("" if np.dtype(dtype) == np.float64 else " or dtype = 'float64'")
        )
    if flat.any():
        e = int(np.argmax(flat))
        raise DegenerateElementError(
            f"{source}: element {e} (nodes {T[e].tolist()}) is degenerate: volume {vol[e]:.3e} m^3 "
            f"for longest edge {lmax[e]:.3e} m; expected a non-flat tetrahedron",
            e,
        )
    inverted = np.nonzero(vol < 0)[0]
    if inverted.size:
        e = int(inverted[0])
        raise InvertedElementError(
            f"{source}: element {e} (nodes {T[e].tolist()}) is inverted: volume {vol[e]:.3e} m^3; "
            f"expected positive orientation (swap two nodes), {inverted.size} inverted element(s) in all",
            e,
        )


def check_material_numbers(source: str, sets, membranes, dtype) -> None:
    """Raise the MaterialError that names the first element set (name, material, density) or
    membrane set (material, with its thickness and density) holding a nonzero number that
    ``dtype`` cannot: one that overflows it (or is not finite), or falls below its smallest normal
    number (float32: 1.2e-38 to 3.4e38), which the engine would turn into inf, 0 or a denormal."""
    f = np.finfo(dtype)
    groups = [(f"element set {s.name!r}", s.material, s.density, _numbers(s.material)) for s in sets]
    groups += [
        (f"membrane set {k}", m, m.density, (*m.params, m.thickness, m.bending_E))
        for k, (_, m) in enumerate(membranes)
    ]
    for where, material, density, values in groups:
        for v in (*values, density):
            size = abs(float(v))
            if size != 0.0 and not float(f.tiny) <= size <= float(f.max):
                raise MaterialError(
                    f"{source}: {where}: {material!r}, density {density:g} kg/m^3: {float(v):.3g} is beyond "
                    f"what {np.dtype(dtype).name} holds ({f.tiny:.2g} to {f.max:.2g}); expected SI "
                    "units (Pa, kg/m^3, m, s)"
                    + ("" if np.dtype(dtype) == np.float64 else " or dtype = 'float64'")
                )


def _numbers(material) -> tuple[float, ...]:
    """A solid material's parameters, with its Prony terms' (α, τ) where it has them, and its
    small-strain Lamé constants (derived: 2 μ of μ = 1e308 overflows)."""
    prony = getattr(material, "prony", ())
    terms = (v for group in prony for term in group for v in term)
    return (*material.params, *terms, material.mu, material.lam)


def node_sizes(
    n_nodes: int, T: np.ndarray, alt: np.ndarray, mem_F: np.ndarray, mem_alt: np.ndarray
) -> np.ndarray:
    """Each node's smallest altitude [m] over its elements, (n_nodes,): tets T (M, 4) of smallest
    altitudes ``alt`` (M,), membranes mem_F (K, 3) of ``mem_alt`` (K,); inf on a node in none."""
    size = np.full(n_nodes, np.inf)
    np.minimum.at(size, np.asarray(T).ravel(), np.repeat(np.asarray(alt, float), 4))
    if len(mem_F):
        np.minimum.at(size, np.asarray(mem_F).ravel(), np.repeat(np.asarray(mem_alt, float), 3))
    return size


def sudden_displacement(cons: dict, size: np.ndarray):
    """The prescribed displacement (``cons``: (node, dof) → (value [m], curve)) whose curve is not 0
    at t = 0, so that the first step moves its node by value × curve(0) (a constant curve: all of
    it), by the most beyond half the node's smallest altitude ``size`` [m]: the node crosses its
    elements and inverts them in that step, whatever the step. (node, dof, value, curve) or None."""
    worst = None
    for (n, d), (value, curve) in cons.items():
        ratio = abs(value * float(curve(0.0))) / size[n]
        if ratio > 0.5 and (worst is None or ratio > worst[0]):
            worst = (ratio, n, d, value, curve)
    return None if worst is None else worst[1:]
