"""The exception hierarchy of cspace: one base, one name per kind of failure.

Each error also subclasses the builtin it stands for, so ``except ValueError``
keeps working for callers that do not know cspace's names.
"""

from __future__ import annotations

__all__ = [
    "CspaceError",
    "InvalidMeshError",
    "EmptyMeshError",
    "NonFiniteError",
    "OpenMeshError",
    "NonManifoldError",
    "DegenerateError",
    "DuplicateFaceError",
    "NotConvexError",
    "GridRangeError",
    "ExactnessError",
    "SceneError",
    "BuildError",
    "OutputError",
    "MeshFileError",
    "MeshFileNotFoundError",
    "OperandTypeError",
    "InvalidQueryError",
    "InvalidArgumentError",
    "ArgumentTypeError",
    "SelfIntersectionError",
    "MissingDependencyError",
    "MemoryBudgetError",
    "UnsupportedError",
]


class CspaceError(Exception):
    """Base class of every error raised by cspace."""


class InvalidMeshError(CspaceError, ValueError):
    """A mesh or point set is not valid input for the operation asked."""


class EmptyMeshError(InvalidMeshError):
    """A mesh or point set has no vertices or no faces."""


class NonFiniteError(InvalidMeshError):
    """A coordinate is NaN or infinite."""


class OpenMeshError(InvalidMeshError):
    """A mesh that must be closed has boundary edges (edges used by one face)."""


class NonManifoldError(InvalidMeshError):
    """An edge is shared by more than two faces, or by two faces in the same direction,
    or a vertex's faces do not form a single fan."""


class DegenerateError(InvalidMeshError):
    """A face has zero area, or a polytope has zero volume (its points are coplanar)."""


class DuplicateFaceError(InvalidMeshError):
    """Two faces use the same vertices."""


class NotConvexError(InvalidMeshError):
    """A mesh passed as convex is not the boundary of its convex hull."""


class GridRangeError(CspaceError, ValueError):
    """A coordinate does not fit the integer range of the snapping grid."""


class ExactnessError(CspaceError, RuntimeError):
    """An internal exact certificate failed: the result would not be exact, so none is given."""


class SceneError(CspaceError, ValueError):
    """A scene file is malformed or describes an impossible problem; the message says where."""


class BuildError(CspaceError, RuntimeError):
    """A C-obstacle of a scene body could not be built; the message names the body and why."""


class OutputError(CspaceError, OSError):
    """An output file cannot be written: unknown format, folder not writable, disk full.
    Nothing is left behind: every file is written to a temporary name and then renamed."""


class MeshFileError(SceneError, InvalidMeshError):
    """A mesh file is missing or cannot be read as triangles; the message names the file
    (and what named it: a scene's key, an argument)."""


class MeshFileNotFoundError(MeshFileError, FileNotFoundError):
    """A mesh file does not exist (also a ``FileNotFoundError``)."""


class OperandTypeError(InvalidMeshError, TypeError):
    """An operand is of a kind no function of cspace takes (not a mesh, points or a path)."""


class InvalidQueryError(CspaceError, ValueError):
    """Query translations are not ``(3,)`` or ``(k, 3)`` numbers."""


class InvalidArgumentError(CspaceError, ValueError):
    """An argument's value is out of its range or not one of its choices; the message names
    the argument and what it takes."""


class ArgumentTypeError(CspaceError, TypeError):
    """An argument is of the wrong type; the message names the argument and what it takes."""


class SelfIntersectionError(InvalidMeshError):
    """A closed mesh intersects itself (two triangles meet beyond a shared edge or vertex):
    it bounds no well-defined solid. The message names two triangles that cross."""


class MissingDependencyError(CspaceError, ImportError):
    """An optional capability needs a package that is not installed (the message names it
    and the pip command); nothing in the default path needs one."""


class MemoryBudgetError(CspaceError, MemoryError):
    """A build would need more memory than its budget (:func:`cspace.memory.memory_budget`):
    it stops before allocating, instead of being killed by the kernel. ``needed`` and
    ``budget`` are in bytes; the message says what needs the memory and how to change the
    budget (``memory=``, ``--memory``, ``$CSPACE_MEMORY``)."""

    def __init__(self, message: str, needed: int = 0, budget: int = 0):
        super().__init__(message)
        self.needed, self.budget = int(needed), int(budget)


class UnsupportedError(CspaceError, NotImplementedError):
    """The input is valid but this operation does not take it (the message says what it
    takes instead): e.g. :func:`cspace.planning.free_space.free_space` on C-obstacles that
    are not made of convex pieces."""
