"""Verification against closed forms in one command (``pliant validate``): references
(strain energies, beam theory, Lamé), the models that meet them, the cases that compare them, and
the report. See docs/validation.md."""

from .cases import CASES, Check
from .report import run_validation

__all__ = ["CASES", "Check", "run_validation"]
