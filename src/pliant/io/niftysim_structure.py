"""The structure of a NiftySim model file (user guide v2.4, App. A): the top-level elements pliant
reads, and which elements may repeat under one parent."""

from __future__ import annotations

__all__ = ["KNOWN_TOP", "warn_repeated"]

# The top-level elements pliant reads (any other is an unsupported feature, refused by name): those
# a file gives once, and those it may repeat, each of which is read.
_TOP_ONCE = {"Nodes", "Elements", "SystemParams", "MSHMesh", "VTKMesh"}
_TOP_MANY = {
    "ElementSet",
    "Constraint",
    "SubMesh",
    "Output",
    "ContactPlate",
    "ContactCylinder",
    "ContactUSProbe",
    "ContactSurface",
    "ShellElements",
    "ShellElementSet",
}
KNOWN_TOP = _TOP_ONCE | _TOP_MANY

# Elements a file may repeat under one parent (each is read); any other element repeated there is
# read once, its first, as NiftySim's tledModel reads it (XMLNode::getChildNode), with a warning.
_REPEATED = _TOP_MANY | {"SubModel", "ClampedNodes", "Motion", "RestrictTo", "Variable"}


def warn_repeated(root, f: str, warnings: list[str]) -> None:
    """A warning for each element repeated under one parent that is read once (its first)."""
    for parent in root.iter():
        tags = [c.tag for c in parent if isinstance(c.tag, str)]
        for tag in dict.fromkeys(tags):
            if tag not in _REPEATED and tags.count(tag) > 1:
                warnings.append(
                    f"{f}: <{parent.tag}> holds {tags.count(tag)} <{tag}>: the first is read, as NiftySim "
                    "reads it; the others are ignored"
                )
