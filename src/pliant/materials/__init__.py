"""Hyperelastic materials (SI units: Pa).

Each class holds validated parameters and its kind code; the stress functions themselves live once,
in C++ (``cpp/include/pliant/materials.hpp``), shared by every backend. Every material accepts
engineering constants ``E`` [Pa] and ``nu`` [-] or its native parameters.

=========================  ==========================================================  ==============
class                      strain energy W                                              native params
=========================  ==========================================================  ==============
NeoHookean                 μ/2 (Ī1 − 3) + K/2 (J − 1)²  (decoupled; NiftySim "NH")      mu, K
MooneyRivlin               C10 (Ī1 − 3) + C01 (Ī2 − 3) + K/2 (J − 1)²                   C10, C01, K
NeoHookeanCoupled          μ/2 (I1 − 3) − μ ln J + λ/2 (ln J)²  (Bonet & Wood; FEBio)   mu, lam
StVenantKirchhoff          λ/2 (tr E)² + μ E:E                                          mu, lam
LinearElastic              λ/2 (tr ε)² + μ ε:ε, small strain                            mu, lam
Polynomial                 Σ Cij (Ī1 − 3)^i (Ī2 − 3)^j, i + j ≤ 2, + K/2 (J − 1)² ("PY")   C10 … C11, K
ArrudaBoyce                μ Σ Ci/λm^(2i−2) (Ī1^i − 3^i) + K/2 ((J²−1)/2 − ln J) ("AB")  mu, lambda_m, K
TransverselyIsotropic      μ/2 (Ī1 − 3) + η/2 (Ī4 − 1)² + K/2 (J − 1)², Ī4 = a·C̄a ("TI")  mu, K, eta, a
=========================  ==========================================================  ==============

Membrane materials (``StVKMembrane``, ``NeoHookeanMembrane``: ModelBuilder.add_membrane) are in
:mod:`pliant.materials.membrane`.
"""

from .hyperelastic import (
    ArrudaBoyce,
    LinearElastic,
    Material,
    MooneyRivlin,
    NeoHookean,
    NeoHookeanCoupled,
    Polynomial,
    StVenantKirchhoff,
    TransverselyIsotropic,
    lame_from_young,
)
from .membrane import MembraneMaterial, NeoHookeanMembrane, StVKMembrane
from .viscoelastic import Viscoelastic

__all__ = [
    "Material",
    "NeoHookean",
    "MooneyRivlin",
    "NeoHookeanCoupled",
    "StVenantKirchhoff",
    "LinearElastic",
    "Polynomial",
    "ArrudaBoyce",
    "TransverselyIsotropic",
    "Viscoelastic",
    "lame_from_young",
    "MembraneMaterial",
    "StVKMembrane",
    "NeoHookeanMembrane",
]
