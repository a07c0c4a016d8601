"""What a solver's runs report: run and relaxation outcomes, and the one contact report (tool force
histories, the last step's contact forces per node, the equilibrium forces of a relaxation)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class RunInfo:
    steps: int
    time: float  # [s]
    element_seconds: float = 0.0  # wall time in kernel 1 (element forces) [s]
    node_seconds: float = 0.0  # wall time in kernel 2 (gather + update + constraints) [s]
    contact_seconds: float = 0.0  # wall time in the contact kernel [s]


@dataclass
class RelaxInfo:
    steps: int
    residual: float  # ||r − f|| on free DOFs / ||(r, reactions)||
    converged: bool
    damping: float  # final adaptive α [1/s]


@dataclass
class ToolHistory:
    """Per tool: ``time`` [s] (steps,), ``force`` [N] (steps, 3), ``torque`` [N·m] (steps, 3) about
    the tool's position, as received by the tool at each step run so far."""

    name: str
    time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    force: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    torque: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))


@dataclass
class PairHistory:
    """Per soft-contact pair of bodies (a, b), a <= b: ``time`` [s] (steps,) and ``force`` [N]
    (steps, 3), the force body a received from body b at each step run so far (self contact,
    a == b: the sum of the forces on the nodes pressed onto the body's own surface); ``relaxed``:
    after ``Solver.relax``, that force at the equilibrium [N] (3,); else None."""

    bodies: tuple[int, int]
    time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    force: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    relaxed: np.ndarray | None = None


@dataclass
class ContactReport:
    """Everything a solver knows about contact with its rigid tools (``Solver.contact_report()``).

    ``tools``: a :class:`ToolHistory` per tool (every step run so far). ``nodes``: the contact
    nodes (user numbering) (n,); ``node_tool``: the tool touching each at the last step (−1: none)
    (n,); ``node_force``: the force that tool exerts on it [N] (n, 3). ``relaxed``: after
    ``Solver.relax``, per tool (force [N], torque [N·m]) at the equilibrium; else None.
    ``pairs``: a :class:`PairHistory` per pair of bodies in soft contact (``Model.contact_pairs``).
    ``soft_nodes``: the soft-contact surface nodes (user numbering) (k,); ``soft_force``: the force
    soft contact exerted on each at the last step [N] (k, 3) (on held DOFs too: what the supports
    carry, ``Model.support_reactions``).
    """

    tools: list[ToolHistory]
    nodes: np.ndarray
    node_tool: np.ndarray
    node_force: np.ndarray
    relaxed: list[tuple[np.ndarray, np.ndarray]] | None = None
    pairs: list[PairHistory] = field(default_factory=list)
    soft_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    soft_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def force(self, k: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """(force [N], torque [N·m]) tool k received: at the equilibrium if the last call was a
        relaxation, else at the last step (zeros before any step)."""
        return tool_force(self.tools, self.relaxed, k)


def tool_force(tools: list[ToolHistory], relaxed, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Tool k's (force [N], torque [N·m]): the relaxed equilibrium's if given, else the last
    recorded step's (zeros before any step). ContactReport.force and Solver.tool_force."""
    if relaxed is not None:
        f, m = relaxed[k]
        return f.copy(), m.copy()
    H = tools[k]
    if len(H.time) == 0:
        return np.zeros(3), np.zeros(3)
    return H.force[-1].copy(), H.torque[-1].copy()
