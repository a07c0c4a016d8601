"""NiftySim's <SystemParams> (user guide v2.4 §3.10): the time step, total time, damping and
default density, and the switches and coefficients of its mesh-based contact."""

from __future__ import annotations

from .niftysim import NiftySimError, _scalar

__all__ = ["SYSTEM", "system_params"]

SYSTEM = {
    "TimeStep",
    "TotalTime",
    "DampingCoeff",
    "Density",
    "HGKappa",
    "DoDeformableCollision",
    "DoSelfCollision",
    "ROM",
    "DeformableFrictionCoefficient",
    "ContactSafetyMargin",
    "RateConstraintDistance",
    "BVType",
    "DoMultiPassContacts",
}


def system_params(root, f: str, unsupported, warnings: list[str], etype: str):
    """<SystemParams>: time step [s], total time [s], damping [1/s], default density [kg/m³]."""
    sp = root.find("SystemParams")
    if sp is None:
        raise NiftySimError("missing <SystemParams>", f)
    params: dict[str, str] = {}
    for c in sp:
        if c.tag not in SYSTEM:
            unsupported(f"SystemParams/{c.tag}", "not implemented in pliant")
            continue
        params.setdefault(c.tag, (c.text or "").strip())  # the first, as NiftySim reads it
    for req in ("TimeStep", "TotalTime", "DampingCoeff"):
        if req not in params:
            raise NiftySimError(f"<SystemParams> lacks <{req}>", f, f"SystemParams/{req}")
    dt = _scalar(params["TimeStep"], f, "SystemParams/TimeStep", float, 0.0)
    total = _scalar(params["TotalTime"], f, "SystemParams/TotalTime", float, 0.0)
    damping = _scalar(params["DampingCoeff"], f, "SystemParams/DampingCoeff", float, 0.0, False)
    default_rho = (
        _scalar(params["Density"], f, "SystemParams/Density", float, 0.0) if "Density" in params else None
    )
    # Mesh-based contact (user guide §3.9.2): between the deformable bodies, and of each with itself.
    collide = tuple(
        bool(_scalar(params.get(k, "0") or "0", f, f"SystemParams/{k}", int, 0, False))
        for k in ("DoDeformableCollision", "DoSelfCollision")
    )
    # Coulomb friction between deformable surfaces (tledUnstructuredContactManager: the deformable
    # surface's coefficient), static and kinetic alike.
    key = "SystemParams/DeformableFrictionCoefficient"
    collide += (_scalar(params.get("DeformableFrictionCoefficient", "0"), f, key, float, 0.0, False),)
    for k in ("ContactSafetyMargin", "RateConstraintDistance"):
        if k in params:
            unsupported(
                f"SystemParams/{k}",
                "NiftySim's contact keeps surfaces apart by offsets; pliant's soft contact has none, its "
                "surfaces touch (docs/contact.md)",
            )
    rom = _scalar(params.get("ROM", "0") or "0", f, "SystemParams/ROM", int, 0, False)
    if rom != 0:  # <ROM>0</ROM> is NiftySim's default, off (user guide §3.10.7)
        unsupported("SystemParams/ROM", "reduced order modelling is not implemented in pliant; ROM 0 runs")
    # How NiftySim searches and resolves its contacts (tledModel::GetBoundingVolumeType,
    # DoMultiPassContactHandling; also <DoDeformableCollision Type="MultiPass">): no physics of
    # their own; pliant's contact has its broad phase and two sweeps a step (docs/contact.md).
    if params.get("BVType", "AABB") not in ("AABB", "OBB"):
        raise NiftySimError(
            f"<BVType> = {params['BVType'][:40]!r}: expected AABB or OBB", f, "SystemParams/BVType"
        )
    for k in ("BVType", "DoMultiPassContacts"):
        if k in params:
            warnings.append(
                f"{f}: {k} ignored (how NiftySim searches its contacts; pliant's contact has its own)"
            )
    if "HGKappa" in params:
        why = "tetrahedra have no hourglass modes" if etype == "H8" else "it applies to H8 elements only"
        warnings.append(f"{f}: HGKappa ignored (hourglass control; {why})")

    return dt, total, damping, default_rho, collide
