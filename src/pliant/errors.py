"""Typed errors. Each names its culprit (file, field, node, element, time) and says what was expected.

All derive from :class:`PliantError`; errors about user input also derive from :class:`ValueError`,
so the command line maps them to exit code 2.
"""

from __future__ import annotations


class PliantError(Exception):
    """Base class of every error pliant raises on purpose."""


class InputError(PliantError, ValueError):
    """Bad user input: a parameter, array or file that does not meet its contract."""


class FileError(InputError):
    """An input file that does not meet its format (a scene, a NiftySim model). ``file``, ``key``
    (a key path or an XML element) and ``line`` name the culprit; the message starts with them:
    ``file:line [key]: what was wrong; what was expected``."""

    def __init__(self, message: str, file: str = "", key: str = "", line: int | None = None):
        if file and message.startswith(f"{file}: "):  # a builder error already naming the file
            message = message[len(file) + 2 :]
        where = file
        if line:
            where += f":{line}"
        if key:
            where += f" [{key}]"
        super().__init__(f"{where}: {message}" if where else message)
        self.file, self.key, self.line = file, key, line


class MaterialError(InputError):
    """Non-physical material parameters (ν ≥ 0.5, non-positive modulus or density...)."""


class MeshError(InputError):
    """A mesh that cannot be simulated (bad indices, NaN coordinates, unreadable file, an element
    given twice, a face shared by three elements or two on the same side of it...)."""


class InvertedElementError(MeshError):
    """A reference element with negative volume (wrong orientation). ``element`` is its index."""

    def __init__(self, message: str, element: int):
        super().__init__(message)
        self.element = element


class DegenerateElementError(MeshError):
    """A reference element with (near) zero volume. ``element`` is its index."""

    def __init__(self, message: str, element: int):
        super().__init__(message)
        self.element = element


class BackendError(InputError):
    """A backend that this build or this machine cannot provide (e.g. CUDA without a GPU)."""


class TimeStepError(InputError):
    """A time step above the critical (stable) one, or otherwise invalid."""


class InstabilityError(PliantError):
    """The run went unstable: NaN, an inverted element (J ≤ 0), or blow-up.

    Attributes: ``time`` [s], ``element`` or ``node`` (user numbering, ``None`` if not applicable),
    ``quantity`` (``"J"``, ``"displacement"``), ``value``.
    """

    def __init__(
        self,
        message: str,
        time: float,
        quantity: str,
        value: float,
        element: int | None = None,
        node: int | None = None,
    ):
        super().__init__(message)
        self.time, self.quantity, self.value = time, quantity, value
        self.element, self.node = element, node


class ConvergenceError(PliantError):
    """A quasi-static solve did not reach its residual tolerance."""


class PliantWarning(UserWarning):
    """A warning about the user's input that does not stop the run (an orphan node, an element that
    limits the time step far below the others...). The command line prints it as one line."""
