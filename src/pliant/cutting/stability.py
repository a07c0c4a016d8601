"""The stable time step after a cut, from the highest frequency of the cut body itself.

A model's dt_critical (smallest h_min / c_d) is the usual estimate for a whole mesh; it is not a
bound. Irons' theorem bounds the highest frequency by the highest of the isolated elements', and
an isolated linear tet (a Kuhn tet) vibrates at 1/0.64 of 2c_d/h_min: pieces a cut makes thin
(a flake one element thick, a corner hanging from a face) come close. So after a cut the step is
checked against the cut body's highest frequency: the largest eigenvalue of M⁻¹K, by Lanczos
(scipy's eigsh) on M^-½ K M^-½ over the free DOFs, K applied as central differences of the
engine's internal forces about the current state (Belytschko, Liu & Moran 2000, §6.3: Δt ≤ 2/ω_max,
reduced for stiffness damping β as in Model.dt_critical).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["highest_frequency", "stable_step"]

# Models with at most this many free DOFs get their highest frequency from the whole matrix.
DENSE_DOFS = 60


def taut(model, dtype: str | None = None):
    """The model itself, or (built again) the same model at ``dtype`` (default its own) with no
    membrane wrinkling, where it differs: a wrinkling membrane's stiffness never exceeds the taut
    one's, and about a flat or compressed state its compressive perturbations meet none, so
    differences there would underestimate the stiffness it has once stretched (docs/engine.md,
    "Wrinkling")."""
    dtype = dtype or np.dtype(model.dtype).name
    if any(m.wrinkling for m in model.membrane_materials) or dtype != np.dtype(model.dtype).name:
        return model.rebuilt(dtype, taut=True)
    return model


def highest_frequency(model, state, rel_tol: float = 1e-3) -> float:
    """ω_max [rad/s] of the linearized model about ``state`` (free DOFs; lumped masses), its
    membranes taut (``taut``); 0 with no free DOF, NaN where the forces are not finite."""
    from scipy.sparse.linalg import LinearOperator, eigsh

    model = taut(model)
    free = ~model.constrained.ravel()
    m = np.repeat(model.mass, 3)[free]
    if not np.all(m > 0):
        m = np.where(m > 0, m, np.inf)  # a massless DOF (an orphan node) has no dynamics
    # Masses relative to their largest finite one: M⁻¹K of extreme densities (1e-300 kg/m³)
    # overflowed inside the operator; ω of the scaled problem is divided by √m_ref at the end.
    finite = m[np.isfinite(m)]
    m_ref = float(finite.max()) if finite.size else 1.0
    scale = 1.0 / np.sqrt(m / m_ref)
    u0 = state.displacements
    X = model.reference_positions
    size = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    probe = model.state()
    # The largest nodal perturbation: 1e-4 of the body in float32 (its force differences keep ~3
    # digits), 1e-6 in float64; small against an element, so that K is the tangent.
    h = (1e-4 if model.dtype == np.float32 else 1e-6) * size

    def force(v):
        u = u0.ravel().copy()
        u[free] += v
        probe.set_displacements(u.reshape(-1, 3))
        return model.internal_forces(probe).ravel()[free]

    def matvec(x):
        y = scale * np.asarray(x, float).ravel()
        peak = np.abs(y).max()
        if not peak > 0:
            return np.zeros_like(y)
        a = h / peak  # the perturbation a·y moves no DOF by more than h
        return scale * (force(a * y) - force(-a * y)) / (2 * a)

    n = int(free.sum())
    if n <= DENSE_DOFS:  # ARPACK needs k < n; a few DOFs are solved whole (n matvecs, symmetrized)
        if n == 0:
            return 0.0  # every DOF prescribed: nothing vibrates
        K = np.column_stack([matvec(e) for e in np.eye(n)])
        if not np.all(np.isfinite(K)):  # forces overflow: no frequency; the run's own check names it
            return math.nan
        return math.sqrt(max(float(np.linalg.eigvalsh((K + K.T) / 2)[-1]), 0.0)) / math.sqrt(m_ref)

    def finite_matvec(x):
        y = matvec(x)
        if not np.all(np.isfinite(y)):
            raise _Overflow
        return y

    A = LinearOperator((n, n), matvec=finite_matvec, dtype=float)
    rng = np.random.default_rng(0)  # a fixed start: the same step every time
    try:
        lam = eigsh(A, k=1, which="LA", tol=rel_tol, v0=rng.standard_normal(n), return_eigenvectors=False)
    except _Overflow:  # as the dense path: no frequency; the run's own check names it
        return math.nan
    return math.sqrt(max(float(lam[0]), 0.0)) / math.sqrt(m_ref)


class _Overflow(Exception):
    """The forces of a probe overflowed (highest_frequency)."""


def stable_step(model, state) -> float:
    """The largest stable Δt [s] of central differences for the model about ``state``: 2/ω_max,
    reduced for stiffness damping β (√(1 + ξ²) − ξ, ξ = β ω_max / 2)."""
    w = highest_frequency(model, state)
    if not w > 0:
        return math.inf
    xi = model.stiffness_damping * w / 2
    return 2.0 / w * (math.sqrt(1 + xi * xi) - xi)
