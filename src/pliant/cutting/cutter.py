"""Running with blades: steps in short runs, after each a cut along what every blade swept."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..checks import shown
from .blade import Blade
from .cut import cut, cut_embedding
from .split import interior_faces

__all__ = ["Cutter", "CutEvent"]


@dataclass
class CutEvent:
    """One cut during a run: time [s], the blade's name, nodes split and faces opened."""

    time: float
    blade: str
    new_nodes: int
    opened_faces: int


@dataclass
class Cutter:
    """Blades that cut while a solver runs. ``every``: steps between cuts (the blade's motion over
    them should stay below an element's size, so that no element is skipped; the default 10 steps
    of a stable Δt move a blade slower than the tissue's wave speed by well under an element).
    ``embedding``: an embedded visual surface (pliant.mesh.Embedding) kept open along the cuts."""

    blades: list = field(default_factory=list)
    every: int = 10
    embedding: object = None
    events: list = field(default_factory=list)
    _faces: tuple = (None, None)  # (model, its interior faces): computed once per topology

    def __post_init__(self):
        blades, self.blades = list(self.blades), []
        for b in blades:
            self.add(b)
        if isinstance(self.every, bool) or not isinstance(self.every, (int, np.integer)) or self.every < 1:
            raise InputError(f"Cutter: every = {shown(self.every)}; expected a whole number of steps >= 1")

    def add(self, blade) -> Blade:
        """Cut with ``blade`` too."""
        if not isinstance(blade, Blade):
            raise InputError(f"Cutter: {shown(blade)} is not a pliant.cutting.Blade")
        self.blades.append(blade)
        return blade

    def cut_now(self, solver, state, t0: float):
        """Cut along what each blade swept from t0 to the state's time [s]; returns the solver and
        state to go on with (new ones after a cut)."""
        for blade in self.blades:
            if self._faces[0] is not state.model:
                self._faces = (state.model, interior_faces(state.model.tets))
            res = cut(state, blade.swept(t0, state.time), solver, self._faces[1])
            if not res.changed:
                continue
            if self.embedding is not None:
                self.embedding = cut_embedding(self.embedding, state.model.tets, res)
            solver, state = res.solver, res.state
            self.events.append(CutEvent(state.time, blade.name, len(res.parent), len(res.faces)))
        return solver, state

    def run(self, solver, state, steps: int):
        """Advance ``state`` by ``steps`` steps of ``solver``, cutting at every step count of the
        state that is a multiple of :attr:`every`, along what the blades swept over the last
        ``every`` steps (_since). A run that ends between two cuts leaves the next one to the next
        run, so the cuts, and the results, do not depend on how the steps are split into runs (a
        scene's frames) nor on a save and restore between cuts. Returns (solver, state): new
        objects once something was cut (the old ones stay as they were at the cut)."""
        done = 0
        while done < steps:
            n = min(self.every - state.steps % self.every, steps - done)
            solver.run(state, steps=n)
            done += n
            if state.steps % self.every == 0:
                solver, state = self.cut_now(solver, state, self._since(state))
        return solver, state

    def _since(self, state) -> float:
        """The time [s] ``every`` steps before the state's, on its run clock (State._clock_times),
        or the clock's epoch if Δt was set since then (a cut's new solver, a user's)."""
        return float(state._clock_times(state.steps - self.every))
