"""Rigid tools and frictional contact with soft bodies.

A tool is a rigid shape (plane, sphere, capsule, box, or any closed triangle mesh through a signed-
distance grid) with Coulomb friction (static μs, kinetic μk) and a trajectory (keyframes, or a pose
set from Python between steps). Soft-body surface nodes that penetrate a tool are moved back onto
its surface after the explicit predictor, with friction (see cpp/include/pliant/contact.hpp); each
tool reports the force [N] and torque [N·m] (about its position) it receives, every step.

Soft bodies also touch each other and themselves (:mod:`pliant.contact.soft`,
``ModelBuilder.set_soft_contact``): node-to-triangle kinematic contact with friction, each pair
conserving momentum, the force between two bodies reported every step.
"""

from .soft import SoftContact, body_labels
from .tools import (
    Box,
    Capsule,
    Cylinder,
    MeshTool,
    Plane,
    RigidTool,
    Sphere,
    quat_align_z,
    quat_from_axis_angle,
    quat_from_matrix,
)

__all__ = [
    "RigidTool",
    "Plane",
    "Sphere",
    "Capsule",
    "Cylinder",
    "Box",
    "MeshTool",
    "quat_from_matrix",
    "quat_from_axis_angle",
    "quat_align_z",
    "SoftContact",
    "body_labels",
]
