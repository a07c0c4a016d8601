"""Peers on the same box, where they are installed: MuJoCo's flex (the ``mujoco`` package) runs the
cantilever of pliant's own check on the very same tetrahedra (a ``flexcomp`` of type "direct"),
and both are compared with the closed form and with each other, and timed over the same simulated
time at the same Δt (simulated seconds per wall second). Newton (the ``newton`` package, on NVIDIA
Warp) runs the same tetrahedra with its semi-implicit solver, on Warp's CPU device, the same way.

The box: a 0.1 × 0.02 × 0.02 m cantilever, E = 100 MPa, ν = 0.3, ρ = 1000 kg/m³, clamped at x = 0,
sagging under gravity (tip deflection 0.02 % of its length: linear elasticity; at 1 MPa, a 1.8 %
sag, MuJoCo's flex departs from the linear answer by 0.16 %, in proportion to the load).
Reference: Timoshenko's uniform-load tip deflection qL⁴/(8EI) + qL²/(2κGA), κ = 5/6 (q = ρ g A)."""

from __future__ import annotations

import contextlib
import importlib.util
import os
import sys
import tempfile
import time
from typing import Any

import numpy as np

from ..materials import LinearElastic
from ..mesh import box_tets
from ..tled import ModelBuilder, Simulation
from .cases import Check

__all__ = ["run_peers"]

L, H, E, NU, RHO, G = 0.1, 0.02, 1.0e8, 0.3, 1000.0, 9.81
# [s]: below both meshes' stable steps (pliant's critical step 1.9e-5 s at 8 cells, 1.3e-5 s at
# 12). Newton's run costs what its steps do (each ~1.5 ms of Python and kernel launches on Warp's CPU
# device): 2e-6 s made the quick run's Newton 42 s, 5e-6 s 19 s, with the same sags (docs/validation.md).
DT = 5e-6
DAMPING = 500.0  # [1/s], mass-proportional in both, to settle onto the static sag


def uniform_load_tip(length=L, depth=H) -> float:
    """Timoshenko tip deflection [m] of a square cantilever under its own weight."""
    area, inertia, shear = depth * depth, depth**4 / 12, E / (2 * (1 + NU))
    q = RHO * G * area
    return q * length**4 / (8 * E * inertia) + q * length**2 / (2 * (5 / 6) * shear * area)


def _beam(cells: int):
    X, T = box_tets((L, H, H), (4 * cells, cells, cells))
    return X, T, np.nonzero(X[:, 0] < 1e-9)[0], np.nonzero(X[:, 0] > L - 1e-9)[0]


def _pliant(X, T, root, tip, settle: float) -> tuple[float, float, np.ndarray]:
    """pliant: tip deflection [m] after ``settle`` s of damped dynamics, simulated seconds per wall
    second over them, and its lumped nodal masses [kg] (for the peer)."""
    b = ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(LinearElastic(E=E, nu=NU), density=RHO)
    b.fix(root)
    b.set_gravity((0.0, 0.0, -G))
    b.damping = DAMPING
    model = b.finalize("float64", threads=1)  # one thread, as MuJoCo's step
    sim = Simulation(model, dt=DT)
    wall = time.perf_counter()
    sim.run(until=settle)
    wall = time.perf_counter() - wall
    return float(-sim.displacements[tip, 2].mean()), settle / wall, model.mass


@contextlib.contextmanager
def _mujoco_warnings(said: list[str]):
    """MuJoCo's warnings (its compiler's, for a flex without equality constraints) into ``said``:
    without a handler MuJoCo prints them and appends them to MUJOCO_LOG.TXT in the working folder."""
    import mujoco

    before = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(said.append)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(before)


def _mujoco(X, T, root, tip, mass, settle: float) -> tuple[float, float, str]:
    """MuJoCo flex on the same nodes and tets, with the same nodal masses: tip deflection [m],
    simulated seconds per wall second, and its version."""
    import mujoco

    pts = " ".join(f"{v:.17g}" for v in X.ravel())
    els = " ".join(str(int(v)) for v in T.ravel())
    xml = f"""<mujoco>
  <option timestep="{DT}" gravity="0 0 {-G}" integrator="Euler"/>
  <worldbody>
    <flexcomp name="beam" type="direct" dim="3" point="{pts}" element="{els}" radius="1e-4"
              mass="{RHO * L * H * H}">
      <edge equality="false"/>
      <elasticity young="{E}" poisson="{NU}" damping="0"/>
      <pin id="{" ".join(str(int(i)) for i in root)}"/>
      <contact selfcollide="none" conaffinity="0" contype="0"/>
    </flexcomp>
  </worldbody>
</mujoco>"""
    said: list[str] = []
    with _mujoco_warnings(said):
        m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    x0 = d.flexvert_xpos.copy()
    if x0.shape != X.shape or not np.allclose(x0, X):
        raise RuntimeError("MuJoCo's flex vertices are not the mesh's nodes in order")
    # pliant's lumped masses ``mass`` (ρ V0 / 4 per corner) on the flex's vertex bodies, and damping
    # c·m per DOF: the same load and damping (the flexcomp spreads its mass evenly: 3 % more sag).
    body = m.flex_vertbodyid[: len(X)]
    free = body > 0  # pinned vertices are the world's
    m.body_mass[body[free]] = mass[free]
    m.dof_damping[:] = DAMPING * m.body_mass[m.dof_bodyid]
    steps = int(round(settle / DT))
    wall = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    wall = time.perf_counter() - wall
    return float(-(d.flexvert_xpos[tip, 2] - x0[tip, 2]).mean()), settle / wall, mujoco.__version__


def _not_importable(*modules: str) -> str:
    """Why the first of ``modules`` (a peer's package, then what it needs) cannot be imported here
    ("" if all can): not installed, or a broken install, which must not stop the report."""
    if importlib.util.find_spec(modules[0]) is None:
        return f"not installed (pip install {modules[0]})"
    for m in modules:
        try:
            importlib.import_module(m)
        except Exception as e:
            return f"installed but not importable ({type(e).__name__}: {e})"
    return ""


def _mujoco_missing() -> str:
    """Why MuJoCo cannot run here ("" if it can): not installed, or a partial install (mujoco 4
    ships in three distributions that share the package folder)."""
    why = _not_importable("mujoco")
    if why:
        return why
    import mujoco

    if not all(hasattr(mujoco, a) for a in ("MjModel", "set_mju_user_warning", "mj_step")):
        return "installed but incomplete (no MjModel: reinstall mujoco)"
    return ""


def _newton_missing() -> str:
    """Why Newton cannot run here ("" if it can): Newton and Warp, which its peer launches."""
    return _not_importable("newton", "warp")


@contextlib.contextmanager
def _native_stderr(said: list[str]):
    """What native code writes to file descriptor 2 meanwhile, into ``said`` (lines)."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            said.extend(tmp.read().decode(errors="replace").splitlines())


_NEWTON_DAMPING = None


def _newton_damping_kernel():
    """A Warp kernel that sets each particle's force to −c m v, the mass-proportional damping
    Newton's solver has no option for: with its semi-implicit (symplectic) Euler the same C = cM
    as pliant's and MuJoCo's. Built on first use (Warp is optional)."""
    global _NEWTON_DAMPING
    if _NEWTON_DAMPING is None:
        import warp as wp

        @wp.kernel
        def mass_damping(
            qd: wp.array(dtype=wp.vec3),
            mass: wp.array(dtype=float),
            c: float,
            f_out: wp.array(dtype=wp.vec3),
        ):
            i = wp.tid()
            f_out[i] = -c * mass[i] * qd[i]

        _NEWTON_DAMPING = mass_damping
    return _NEWTON_DAMPING


def _newton(X, T, root, tip, settle: float) -> tuple[float, float, str]:
    """Newton's semi-implicit solver on the same nodes and tets (its stable Neo-Hookean, Smith et
    al. 2018, with the Lamé parameters of their §3.4 that match linear elasticity at small strain:
    μ' = 4μ/3, λ' = λ + 5μ/6), its own lumped masses (ρ V0 / 4 per corner, as pliant's), the root
    nodes given zero mass (fixed), mass-proportional damping by the kernel above: tip deflection
    [m], simulated seconds per wall second, and its version. Float32, Warp's CPU device."""
    import warp as wp

    # Before Newton initializes Warp: warnings only (30, LOG_WARNING), so no banner and no "Module ...
    # load on device" lines in pliant's output.
    wp.config.log_level = 30
    said: list[str] = []
    with _native_stderr(said):  # Warp's C++ says on stderr when there is no CUDA driver: moot here
        wp.init()
    import newton

    mu, lam = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    # Any: Newton's annotation names warp._src.types.quatf, which Warp's public quatf does not match
    # for mypy (a plain tuple, which the annotation allows, fails at run time).
    identity: Any = wp.quat_identity()
    b = newton.ModelBuilder(up_axis=newton.Axis.Z, gravity=(0.0, 0.0, -G))
    b.add_soft_mesh(
        pos=(0.0, 0.0, 0.0),
        rot=identity,
        scale=1.0,
        vel=(0.0, 0.0, 0.0),
        vertices=[(float(x), float(y), float(z)) for x, y, z in X],
        indices=[int(i) for i in T.ravel()],
        density=RHO,
        k_mu=4 * mu / 3,
        k_lambda=lam + 5 * mu / 6,
        k_damp=0.0,
        particle_radius=1e-4,  # its default (0.1 m) would make contacts across the whole beam
    )
    if b.particle_count != len(X) or b.tet_count != len(T):
        raise RuntimeError(
            f"Newton took {b.particle_count} nodes / {b.tet_count} tets of {len(X)} / {len(T)}"
        )
    for i in root:
        b.particle_mass[int(i)] = 0.0
    model = b.finalize(device="cpu")
    solver = newton.solvers.SolverSemiImplicit(model, enable_tri_contact=False)
    s0, s1, control = model.state(), model.state(), model.control()
    damping = _newton_damping_kernel()

    def step() -> None:
        nonlocal s0, s1
        wp.launch(
            damping,
            dim=len(X),
            inputs=[s0.particle_qd, model.particle_mass, DAMPING],
            outputs=[s0.particle_f],
            device="cpu",
        )
        solver.step(s0, s1, control, None, DT)
        s0, s1 = s1, s0

    step()  # compiles (or loads) Warp's kernels: not timed
    steps = int(round(settle / DT)) - 1
    wall = time.perf_counter()
    for _ in range(steps):
        step()
    wp.synchronize()
    wall = time.perf_counter() - wall
    if s0.particle_q is None:
        raise RuntimeError("Newton's state has no particle positions")
    q = s0.particle_q.numpy()
    return float(-(q[tip, 2] - X[tip, 2]).mean()), (settle - DT) / wall, newton.__version__


def run_peers(quick: bool) -> tuple[list[Check], list[dict]]:
    """Checks (pliant against the closed form, and against MuJoCo and Newton on the same mesh where
    they are installed) and the peers table: per simulator its tip deflection over the closed form
    and its simulated seconds per wall second (or why it did not run)."""
    cells, settle = (2, 0.06) if quick else (3, 0.12)  # settled to 6e-7 and 2e-10 (1.5× as long)
    X, T, root, tip = _beam(cells)
    ref = uniform_load_tip()
    ours, speed, mass = _pliant(X, T, root, tip, settle)
    table = [
        {"peer": "pliant", "ran": True, "ratio": ours / ref, "speed": speed, "note": "cpu, float64, 1 thread"}
    ]
    peers = (  # name, why not here, run, case, note, why the tolerance, tolerance
        (
            "mujoco",
            _mujoco_missing,
            lambda: _mujoco(X, T, root, tip, mass, settle),
            "MuJoCo flex",
            "flex, Euler",
            "the same linear tets, masses and damping in two independent codes, linear regime: "
            "measured 1.3e-5 apart on 192 tets, 9.3e-6 on 648 (MuJoCo's flex is geometrically "
            "nonlinear: the gap grows with the load)",
            1e-4,
        ),
        (
            "newton",
            _newton_missing,
            lambda: _newton(X, T, root, tip, settle),
            "Newton semi-implicit",
            "semi-implicit, Warp CPU device, float32",
            "the same tets and damping, Newton's stable Neo-Hookean matched to the linear moduli, in "
            "float32 (the 1.8e-5 m sag is about 10,000 float32 steps of the 0.02 m heights): measured "
            "3.4e-5 apart on 192 tets, 2.9e-4 on 648",
            1e-3,
        ),
    )
    rows: list[Check] = []
    for name, missing, run, case, note, why_tolerance, tolerance in peers:
        why = missing()
        if why:
            table.append({"peer": name, "ran": False, "note": why})
            continue
        theirs, their_speed, version = run()
        table.append(
            {
                "peer": f"{name} {version}",
                "ran": True,
                "ratio": theirs / ref,
                "speed": their_speed,
                "note": note,
            }
        )
        label = case.split()[0]
        rows.append(
            Check(
                f"peers: {case}, same mesh",
                f"pliant's tip sag against {label}'s ({len(T)} tets)",
                ours,
                theirs,
                "m",
                why_tolerance,
                tolerance=tolerance,
            )
        )
    return rows, table
