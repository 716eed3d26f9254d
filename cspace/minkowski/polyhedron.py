"""The results of the exact sums: :class:`SumPolyhedron` and :class:`ExactVolume`.

A :class:`SumPolyhedron` holds the sum's boundary as exact homogeneous integer points
(``points_exact``) and their float64 rounding (``vertices``, ``(n, 3)``, scene units, world frame),
int64 faces counter-clockwise seen from outside, its shells and holes, non-manifold edges and
vertices, the stage timings and ``error_bound``. Volumes are exact rationals (:func:`_six_volume`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property
from math import gcd

import numpy as np

from ..geometry.exact import Grid
from ..geometry.tritri import _cross, _dot

__all__ = ["SumPolyhedron"]


@dataclass(frozen=True, eq=False)
class SumPolyhedron:
    """The Minkowski sum A ⊕ B as a closed, oriented polyhedral surface.

    The surface is computed exactly on ``grid`` (every vertex is a rational point, every
    decision an exact predicate) and then rounded to float64 for :attr:`vertices`.

    Attributes
    ----------
    vertices : (n, 3) float64
        Vertex positions, scene units: the exact vertices rounded to the nearest float64.
    faces : (m, 3) int64
        Triangles, counter-clockwise seen from outside the solid (inner shells of holes face
        into the hole). Every edge is used by an even number of triangles with balanced
        orientation (a closed 2-cycle), also at non-manifold edges.
    face_facet : (m,) int64
        The polygon facet each triangle belongs to.
    facet_kind : (f,) int8
        Kind of each polygon facet: an index into ``cspace.SUPERSET_KINDS`` (translated,
        corner, edge), the same kinds as ``cspace.FACET_KINDS`` for convex pairs.
    facet_source_a, facet_source_b : (f, 2) int64
        ``(dimension, index)`` of the features of A and B the facet comes from (for a facet
        merged from several coplanar superset facets: the first of them).
    shell : (m,) int64
        Connected shell of each triangle; ``shell_is_hole[s]`` says whether shell ``s`` bounds a
        polyhedral hole (a bounded void) rather than the outside.
    shell_is_hole : (s,) bool
    nonmanifold_edges : (k, 2) int64
        Vertex pairs ``u < v`` of edges used by four or more triangles.
    nonmanifold_vertices : (k,) int64
        Vertices whose neighbourhood on the surface is not one disc (double vertices,
        pinches), including the endpoints of non-manifold edges.
    rounding_self_intersections : (k, 2) int64
        Pairs of triangles that intersect improperly after rounding to float64 although
        they did not in the exact result (empty when rounding created none).
    rounding : (3,) float64
        Per axis, a bound on how far rounding to float64 moved a vertex (half the ulp of the
        moved coordinates; zero when every vertex is exactly a float64).
    grid : Grid
        The snapping grid of the inputs.
    points_exact : list or ConvexPolytope
        The exact vertices: homogeneous ``(X, Y, Z, W)`` Python ints in grid units, one per
        row of :attr:`vertices` (for convex pairs: the CVMS polytope, integer vertices).
    volume_exact : Fraction
        Exact enclosed volume (holes subtracted), scene units cubed, of the exact surface
        (computed on first access).
    convex : bool
        True when both operands were convex and CVMS produced the result.
    stats : dict
        Seconds per stage (``superset``, ``planes``, ``intersections``, ``arrangements``,
        ``traversal``, ``membership``, ``output``, ``rounding_check``, ``total``) and sizes
        (``superset_facets``: the convolution's; ``reduced_facets``: those the trimming keeps,
        :func:`~cspace.minkowski.superset.reduced_superset`; ``superset_triangles``: the kept
        ones' triangles; ``n_planes``, ``candidate_pairs``, ``cut_pairs``, ``subfacets``,
        ``shells``, ``membership_tests``, ``output_triangles``); for A made of several
        bodies, ``bodies`` and ``thin_features`` (how many of them are features thinner than
        the grid step, each grown by a step).
    pieces : tuple of ClosedMesh
        When A was several closed bodies (meeting at faces, edges or vertices, crossing
        each other, or with features thinner than the grid step: see
        :func:`cspace.minkowski_sum`), those bodies, on A's grid; this surface is then the
        exact boundary of the union of their sums. Empty for one body.
    operand_b : ConvexPolytope or None
        B as summed, with :attr:`pieces` (for :attr:`parts`).
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_facet: np.ndarray
    facet_kind: np.ndarray
    facet_source_a: np.ndarray
    facet_source_b: np.ndarray
    shell: np.ndarray
    shell_is_hole: np.ndarray
    nonmanifold_edges: np.ndarray
    nonmanifold_vertices: np.ndarray
    rounding_self_intersections: np.ndarray
    grid: Grid
    points_exact: list = field(repr=False)
    convex: bool = False
    stats: dict = field(default_factory=dict, repr=False)
    rounding: np.ndarray = field(default_factory=lambda: np.zeros(3), repr=False)
    pieces: tuple = field(default=(), repr=False)
    operand_b: object = field(default=None, repr=False)
    #: How a body of :attr:`pieces` is summed with :attr:`operand_b` (set by
    #: :func:`cspace.minkowski_sum`, which this module does not import).
    sum_of_body: object = field(default=None, repr=False)

    @cached_property
    def parts(self) -> tuple:
        """The sum of each body of A, when A was several (:attr:`pieces`; computed on first
        access, each an exact :class:`SumPolyhedron`); else ``(self,)``. Their union is this
        surface's solid."""
        if len(self.pieces) < 2:
            return (self,)
        return tuple(self.sum_of_body(body) for body in self.pieces)

    @cached_property
    def volume_exact(self) -> Fraction:
        """Exact enclosed volume (holes subtracted) of the exact surface, scene units cubed."""
        if self.convex:
            P = self.points_exact
            return ExactVolume(Fraction(P.volume6()) / 6 * Fraction(2) ** (3 * self.grid.exponent))
        six = _six_volume(self.points_exact, self.faces)
        return ExactVolume(six / 6 * Fraction(2) ** (3 * self.grid.exponent))

    @property
    def volume(self) -> float:
        """Enclosed volume (float of :attr:`volume_exact`)."""
        return float(self.volume_exact)

    def __repr__(self) -> str:
        return (
            f"SumPolyhedron(vertices={len(self.vertices)}, faces={len(self.faces)}, "
            f"holes={self.n_holes}, nonmanifold_edges={len(self.nonmanifold_edges)}, "
            f"convex={self.convex}"
            + (f", bodies={len(self.pieces)})" if self.pieces else ")")
        )

    @property
    def n_holes(self) -> int:
        return int(np.count_nonzero(self.shell_is_hole))

    @property
    def is_manifold(self) -> bool:
        return len(self.nonmanifold_edges) == 0 and len(self.nonmanifold_vertices) == 0

    @property
    def error_bound(self) -> float:
        """Hausdorff distance bound between this sum and the sum of the unsnapped inputs
        (twice the grid's point error bound), plus half a float64 ulp of rounding per
        coordinate of :attr:`vertices`, plus ``sqrt(3)`` steps per flat operand thickened
        (``stats['thickened_operands']``; the sum then holds the exact one), plus how far the
        hulls of operands that snapping bent may exceed them (``stats['hull_excess']``,
        :func:`cspace.mesh.convex.convex_within_bound`; the sum then holds the exact one)."""
        scale = float(np.abs(self.vertices).max()) if len(self.vertices) else 0.0
        thick = self.stats.get("thickened_operands", 0) * np.sqrt(3.0) * self.grid.step
        return (2.0 * self.grid.point_error_bound + float(np.spacing(scale)) + thick
                + self.stats.get("hull_excess", 0.0))

    def to_trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


class ExactVolume(Fraction):
    """An exact volume: a :class:`fractions.Fraction` that prints whatever its size.

    Python refuses to turn an integer of more than 4300 digits into text; the exact volume
    of a sum with many crossing planes has numerators and denominators that long. Such a
    volume prints as its float and the sizes of its terms; arithmetic is Fraction's.
    """

    _LIMIT_BITS = 4000 * 3  # about 3600 digits: comfortably inside Python's 4300

    def _too_long(self) -> bool:
        return max(abs(self.numerator), self.denominator).bit_length() > self._LIMIT_BITS

    def _digits(self) -> str:
        n, d = abs(self.numerator).bit_length(), self.denominator.bit_length()
        return f"about {int(n * 0.30103) + 1} / {int(d * 0.30103) + 1} digits"

    def __str__(self) -> str:
        if self._too_long():
            return f"{float(self)!r} (exact fraction of {self._digits()})"
        return super().__str__()

    def __repr__(self) -> str:
        if self._too_long():
            return f"ExactVolume({float(self)!r}, {self._digits()})"
        return f"ExactVolume({super().__str__()})"


def _six_volume(points: list, faces: np.ndarray) -> Fraction:
    """Six times the volume the triangles enclose, exactly, in grid units cubed (homogeneous
    grid points ``(x, y, z, w)``)."""
    num, den = 0, 1
    for a, b, c in faces.tolist():
        P, Q, R = points[a], points[b], points[c]
        det = _dot(P[:3], _cross(Q[:3], R[:3]))
        if det:
            w = P[3] * Q[3] * R[3]
            g = gcd(den, w)
            num, den = num * (w // g) + det * (den // g), den * (w // g)
    return Fraction(num, den)


def _volume_sign(points: list, faces: np.ndarray) -> int:
    """Exact sign of the volume the triangles enclose (homogeneous grid points).

    Float filter first: six times the volume is the sum over the triangles of the triple
    products ``a . (b x c)`` of their corners. On coordinates correctly rounded from the exact
    ratios (relative error ``u = 2**-53``), each computed triple product is within ``(3u +
    5u + O(u^2)) m`` of the exact one (three rounded factors, then at most five roundings of
    the products and sums), ``m`` the sum of the absolute values of its six products; the
    sum of the ``n`` terms adds at most ``(n - 1) u`` of the sum of their magnitudes. So the
    computed sum is within ``(n + 8) u (1 + O(u)) M`` (``M`` the sum of the ``m``), and its
    sign is the exact one when ``|sum| > 2 (n + 10) u M`` (the factor 2 covers the rounding
    of ``M``). Coordinates beyond ``[2**-300, 2**300]`` in magnitude (other than 0) skip the
    filter (no under- or overflow). Else the exact sum (:func:`_six_volume`) decides."""
    if len(faces):
        ids = np.unique(faces)
        P = np.array([(p[0] / p[3], p[1] / p[3], p[2] / p[3]) for p in (points[i] for i in ids.tolist())],
                     dtype=np.float64).reshape(-1, 3)
        a = np.abs(P)
        if (((a == 0) | ((a >= 2.0 ** -300) & (a <= 2.0 ** 300))).all()):
            F = np.searchsorted(ids, faces)
            A, B, C = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
            total = float(np.einsum("ij,ij->i", A, np.cross(B, C)).sum())
            aA, aB, aC = np.abs(A), np.abs(B), np.abs(C)
            mag = float((aA[:, 0] * (aB[:, 1] * aC[:, 2] + aB[:, 2] * aC[:, 1])
                         + aA[:, 1] * (aB[:, 2] * aC[:, 0] + aB[:, 0] * aC[:, 2])
                         + aA[:, 2] * (aB[:, 0] * aC[:, 1] + aB[:, 1] * aC[:, 0])).sum())
            if abs(total) > 2.0 * (len(faces) + 10) * 2.0 ** -53 * mag:
                return 1 if total > 0 else -1
    six = _six_volume(points, faces)
    return (six > 0) - (six < 0)
