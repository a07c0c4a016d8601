"""NiftySim's ball_ball.xml (tests/data/niftysim_ball_ball.xml, as in ../shared/niftysim; two
Neo-Hookean balls of 1 m radius pushed 0.2 m into each other by ramped displacements of their far
caps, Δt = 0.1 ms, 1 s) without its contact, three ways, compared at its ten output times as the
largest nodal distance over the largest displacement:

- pliant (float32, the import's precision), at Δt and at Δt/2;
- an independent float64 TLED written here in numpy from the formulas (F = I + Σ u ∇N, the decoupled
  Neo-Hookean's S, f = V0 F S ∇N, lumped mass, NiftySim's central-difference update
  u⁺ = A (−f) + B u + C u⁻ with A, B, C per node, the caps' displacements imposed after it);
- the same with A, B, C rounded to float32 one by one, as NiftySim's
  tledCentralDifferenceTimeStepperCPU stores them: B + C − 1 is then not 0 but ±1e-7, a spring of
  ω² ≈ (B + C − 1)/Δt² that grows a rigid motion (docs/engine.md, "Precision of float32 runs").

With ``--niftysim PROGRAM`` it also runs NiftySim (PROGRAM -x in a scratch folder) at Δt, Δt/2 and
Δt/4 and compares its U.txt with pliant's at Δt (NiftySim's frame k lies one step later, which
accounts for at most 0.1 % at the first frame). Contact is left out (``--contact`` keeps it, for
pliant and NiftySim only). About 2 minutes (the numpy reference runs 10,000 steps twice).

    python benchmarks/niftysim_ball_ball.py
    python benchmarks/niftysim_ball_ball.py --niftysim /path/to/niftysim
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import numpy as np

import pliant as pl
from pliant.io.niftysim import load_niftysim

MODEL = Path(__file__).resolve().parents[1] / "tests" / "data" / "niftysim_ball_ball.xml"
FRAMES = 10


def _model_text(contact: bool, dt_divisor: int = 1) -> str:
    """ball_ball.xml with ten outputs of U, without its DoDeformableCollision unless ``contact``,
    at Δt / dt_divisor."""
    s = MODEL.read_text()
    if not contact:
        s = re.sub(r"<DoDeformableCollision>.*?</DoDeformableCollision>", "", s, flags=re.S)
    dt = float(re.search(r"<TimeStep>([^<]*)</TimeStep>", s)[1]) / dt_divisor
    total = float(re.search(r"<TotalTime>([^<]*)</TotalTime>", s)[1])
    s = re.sub(r"<TimeStep>[^<]*</TimeStep>", f"<TimeStep>{dt:.10g}</TimeStep>", s)
    freq = round(total / dt) // FRAMES
    return s.replace(
        "<SystemParams>", f'<Output Freq="{freq}"><Variable>U</Variable></Output><SystemParams>', 1
    )


def _pliant(text: str, folder: Path) -> np.ndarray:
    """pliant's displacements [m] at the ten output times, (FRAMES, N, 3)."""
    path = folder / "ball_ball.xml"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_niftysim(path)
        sim = pl.Simulation(scene.builder.finalize("float32"), dt=scene.dt)
    total = scene.duration
    out = []
    for k in range(FRAMES):
        sim.run(until=total * (k + 1) / FRAMES)
        out.append(sim.displacements.copy())
    return np.array(out)


def _reference(text: str, niftysim_coefficients: bool) -> np.ndarray:
    """The numpy TLED's displacements [m] at the ten output times, (FRAMES, N, 3)."""
    grab = lambda pattern: re.search(pattern, text)[1]  # noqa: E731
    X = np.array(grab(r'<Nodes DOF="3" NumNodes="\d+">([^<]*)</Nodes>').split(), float).reshape(-1, 3)
    T = np.array(grab(r'<Elements NumEls="\d+" Type="T4">([^<]*)</Elements>').split(), int).reshape(-1, 4)
    mu, K = map(float, grab(r'<ElasticParams NumParams="2">([^<]*)</ElasticParams>').split())
    rho, dt = float(grab(r"<Density>([^<]*)</Density>")), float(grab(r"<TimeStep>([^<]*)</TimeStep>"))
    total, alpha = (
        float(grab(r"<TotalTime>([^<]*)</TotalTime>")),
        float(grab(r"<DampingCoeff>([^<]*)</DampingCoeff>")),
    )
    caps = [
        (np.array(m[2].split(), int), int(re.search(r'DOF="(\d)"', m[1])[1]), float(m[3].split()[0]))
        for m in re.finditer(
            r"<Constraint([^>]*)>\s*<Nodes>([^<]*)</Nodes>\s*<Magnitudes[^>]*>([^<]*)</Magnitudes>", text
        )
    ]
    E = X[T]
    D = np.stack([E[:, 1] - E[:, 0], E[:, 2] - E[:, 0], E[:, 3] - E[:, 0]], axis=2)
    V0 = np.linalg.det(D) / 6
    Dinv = np.linalg.inv(D)  # row j: ∇N of corner j + 1
    dN = np.concatenate([-Dinv.sum(1, keepdims=True), Dinv], axis=1)  # (M, 4, 3)
    n = len(X)
    m = np.zeros(n)
    np.add.at(m, T.ravel(), np.repeat(rho * V0 / 4, 4))
    if niftysim_coefficients:  # as tledCentralDifferenceTimeStepperCPU computes and stores them
        f32, m32, dt32, a32 = np.float32, m.astype(np.float32), np.float32(dt), np.float32(alpha)
        A = f32(1) / (m32 / dt32 / dt32 + a32 * m32 / f32(2) / dt32)
        B = f32(2) * m32 * A / dt32 / dt32
        C = a32 * m32 * A / f32(2) / dt32 - B / f32(2)
        A, B, C = (np.asarray(c, np.float64) for c in (A, B, C))
    else:
        A = 1 / (m / dt**2 + alpha * m / (2 * dt))
        B, C = 2 * m * A / dt**2, alpha * m * A / (2 * dt) - m * A / dt**2
    u, u_prev, eye, out = np.zeros((n, 3)), np.zeros((n, 3)), np.eye(3), []
    steps = round(total / dt)
    for step in range(1, steps + 1):
        F = eye + np.einsum("mai,maj->mij", u[T], dN)
        Cg = np.einsum("mki,mkj->mij", F, F)
        J, Ci, I1 = np.linalg.det(F), np.linalg.inv(Cg), np.einsum("mii->m", Cg)
        S = (
            mu * J[:, None, None] ** (-2 / 3) * (eye - I1[:, None, None] / 3 * Ci)
            + K * (J * (J - 1))[:, None, None] * Ci
        )
        fe = V0[:, None, None] * np.einsum("mij,mjk,mak->mai", F, S, dN)
        f = np.zeros((n, 3))
        np.add.at(f, T, fe)
        u_next = -A[:, None] * f + B[:, None] * u + C[:, None] * u_prev
        for nodes, dof, value in caps:
            u_next[nodes, dof] = value * step * dt / total  # LoadShape RAMP
        u_prev, u = u, u_next
        if step % (steps // FRAMES) == 0:
            out.append(u.copy())
    return np.array(out)


def _niftysim(program: str, text: str, folder: Path) -> np.ndarray | None:
    """NiftySim's U.txt at the ten output times, (FRAMES, N, 3); None if it wrote none."""
    work = folder / "niftysim"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir()
    (work / "ball_ball.xml").write_text(text)
    subprocess.run([program, "-x", "ball_ball.xml"], cwd=work, capture_output=True, timeout=600)
    if not (work / "U.txt").is_file():
        return None
    U = np.loadtxt(work / "U.txt", ndmin=2)  # a row per DOF, a column per output
    return U.T.reshape(U.shape[1], -1, 3)


def _apart(a: np.ndarray, b: np.ndarray) -> str:
    """Largest nodal distance over b's largest displacement, per frame, in %."""
    d = np.linalg.norm(a - b, axis=2).max(axis=1) / np.linalg.norm(b, axis=2).max(axis=1)
    return " ".join(f"{100 * x:.3g}" for x in d)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--niftysim", help="a NiftySim executable to run as well")
    ap.add_argument("--contact", action="store_true", help="keep DoDeformableCollision (no numpy reference)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        p1, p2 = _pliant(_model_text(args.contact), folder), _pliant(_model_text(args.contact, 2), folder)
        print("% of the largest displacement, frames at t = 0.1 … 1 s")
        print(f"pliant Δt/2 vs pliant Δt:                 {_apart(p2, p1)}")
        ref = None
        if not args.contact:
            ref = _reference(_model_text(False), niftysim_coefficients=False)
            ref32 = _reference(_model_text(False), niftysim_coefficients=True)
            print(f"pliant vs float64 reference:              {_apart(p1, ref)}")
            print(f"reference, NiftySim's float32 A B C, vs it: {_apart(ref32, ref)}")
        if args.niftysim:
            for k in (1, 2, 4):
                U = _niftysim(args.niftysim, _model_text(args.contact, k), folder)
                got = "wrote no U.txt" if U is None else _apart(U, p1)
                print(f"NiftySim Δt/{k} vs pliant Δt:               {got}")


if __name__ == "__main__":
    main()
