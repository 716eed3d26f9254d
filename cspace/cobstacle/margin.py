"""Outward rounding: the margin that makes a stored C-obstacle hold the true one.

Snapping moves every input coordinate by at most half a grid step, in either direction. The
exact C-obstacle of the snapped inputs, ``CO' = O' ⊕ (c' - R')``, is therefore within a small
Hausdorff distance of the true ``CO = O ⊕ (c - R)`` of the float input, but on *both* sides:
where two sums only touch (a comb's gap exactly as wide as the robot), snapping can open a
slit of free space that does not exist, and a planner would be told "free" where the robot
collides. A bound on the C-obstacle's error does not bound the error of its free space.

So every C-obstacle is built grown by a box: ``CO' ⊕ [-g, g]`` (grid steps, per axis), which
costs nothing extra in kind because ``CO' ⊕ box = O' ⊕ (c' - (R' ⊕ box))`` (grow the convex
robot part, or the convex obstacle, or each triangle pair's piece by the box's support).

Invariants, per axis ``i`` with grid step ``s`` (:class:`Margin`):

- ``deviation[i]`` is the exact largest ``|x - snap(x)|`` over the obstacle's, the robot's
  and the reference point's coordinates on that axis, summed over the three operands (each is
  snapped once): every point of ``CO`` is within ``deviation`` (per axis) of a point of ``CO'``.
- ``steps[i] * s >= deviation[i] + rounding``, where ``rounding`` bounds the float64 rounding
  of an output mesh's vertices (zero for outputs kept as exact integers: convex polytopes,
  triangle pairs). Hence ``CO ⊆`` the stored C-obstacle: **no false free**.
- Conversely every stored point is within ``deviation + steps * s + rounding`` (per axis) of
  ``CO``: :attr:`Margin.error_bound` is that box's half-diagonal, the largest distance by which
  a reported collision can be false.

Inputs already on the grid (dyadic coordinates a grid step can represent) have deviation
zero; their exactly stored C-obstacles (convex, pieces, pairs) get no margin at all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from fractions import Fraction

import numpy as np

from ..geometry.exact import Grid
from ..geometry.snapping import grow_points, snap_deviation

__all__ = ["Margin"]


@dataclass(frozen=True)
class Margin:
    """The box a C-obstacle is grown by so that it holds the C-obstacle of the float input.

    Attributes
    ----------
    steps : (3,) int64
        Half-sizes of the box, grid steps per axis (``g``).
    deviation : (3,) float64
        Summed largest snapping moves of the operands per axis, scene units (exact).
    grid : Grid
    rounding : float
        Bound on the float64 rounding of the stored vertices (0 when stored exactly).
    conservative : bool
        Whether the box was chosen to hold the true C-obstacle (False: no growth asked for).
    """

    steps: tuple
    deviation: tuple
    grid: Grid
    rounding: float = 0.0
    conservative: bool = True

    @classmethod
    def none(cls, grid: Grid) -> "Margin":
        """No growth: the C-obstacle of the snapped inputs as it is (two-sided error)."""
        return cls((0, 0, 0), (0.0, 0.0, 0.0), grid, 0.0, False)

    @classmethod
    def for_deviation(cls, deviation, grid: Grid, *, rounded: bool) -> "Margin":
        """The least box covering ``deviation`` (per axis, scene units: floats or exact
        Fractions) plus, when the result is stored as float64 vertices (``rounded``), their
        rounding.

        Rounded outputs lie within ``2**(bits + 2)`` steps of the grid's origin (three snapped
        operands and the box), below ``2**W`` in magnitude (``Grid.magnitude_exponent``), so
        half an ulp there is at most ``2**(W - 53)`` (``2**(bits - 51)`` steps at origin 0).
        """
        dev = [Fraction(d) for d in deviation]
        rounding = math.ldexp(1.0, grid.magnitude_exponent - 53) if rounded else 0.0
        s = Fraction(grid.step)
        steps = tuple(int(-(-(d + Fraction(rounding)) // s)) for d in dev)
        # Stored as floats rounded up, so that the stated bound stays a bound.
        up = tuple(float(d) if Fraction(float(d)) >= d else math.nextafter(float(d), math.inf)
                   for d in dev)
        return cls(steps, up, grid, rounding)

    @classmethod
    def for_operands(cls, grid: Grid, *point_sets, rounded: bool) -> "Margin":
        """Margin for operands given as float point sets, each snapped once onto ``grid``
        (their deviations add up, exactly)."""
        dev = [Fraction(0)] * 3
        for P in point_sets:
            try:
                P = np.asarray(P, dtype=np.float64)
            except (TypeError, ValueError):
                continue
            if P.ndim != 2 or P.shape[1] != 3 or not np.isfinite(P).all():
                continue  # not a point set: validating the operand refuses it, by name
            dev = [a + Fraction(float(b)) for a, b in zip(dev, snap_deviation(P, grid))]
        return cls.for_deviation(dev, grid, rounded=rounded)

    def without_growth(self) -> "Margin":
        """The same deviations with no box: the snapped inputs' C-obstacle as it is, whose
        error (:attr:`error_bound`) is then two-sided."""
        return Margin((0, 0, 0), self.deviation, self.grid, self.rounding, False)

    def at_least(self, steps: int) -> "Margin":
        """The same deviations with every half-size raised to at least ``steps``."""
        return Margin(tuple(max(int(g), steps) for g in self.steps), self.deviation, self.grid,
                      self.rounding, self.conservative)

    def with_rounding(self, rounding) -> "Margin":
        """The same box, with the measured rounding bound of the stored vertices (per axis,
        their largest is kept)."""
        r = float(np.max(rounding)) if np.size(rounding) else 0.0
        return Margin(self.steps, self.deviation, self.grid, max(r, self.rounding),
                      self.conservative)

    @property
    def g(self) -> np.ndarray:
        """``(3,)`` int64 half-sizes in grid steps."""
        return np.asarray(self.steps, dtype=np.int64)

    @property
    def any(self) -> bool:
        return any(self.steps)

    def grow_ints(self, ints: np.ndarray) -> np.ndarray:
        """``(n * k, 3)`` int64: every point plus every corner (hull them for the grown set)."""
        return grow_points(ints, self.steps)

    def grow(self, poly):
        """A convex polytope grown by the box (exact hull on the grid), or itself.

        The hull of ``grow_ints(poly.ints)`` as :meth:`ConvexPolytope.from_ints` makes it; with
        every half-size positive it is found as the CVMS sum of the polytope and the box (the
        sum's facets are the hull's), not by a hull of the grown points."""
        if not self.any:
            return poly
        from ..mesh.convex import ConvexPolytope

        if min(self.steps) > 0:
            from ..minkowski.cvms import convex_minkowski_sum

            box = ConvexPolytope.box(self.steps, grid=poly.grid.vectors)
            if box is not None:
                grown = convex_minkowski_sum(poly, box).polytope.canonical()
                return replace(grown, name=poly.name, excess=0.0, _cache={})
        return ConvexPolytope.from_ints(self.grow_ints(poly.ints), grid=poly.grid,
                                        name=poly.name)

    @property
    def error_bound(self) -> float:
        """Largest distance (scene units) from a point of the stored C-obstacle to the true
        C-obstacle of the float input: the half-diagonal of the box
        ``deviation + steps * step + rounding``, rounded up. The stored C-obstacle holds the
        true one whenever ``steps`` is non-zero or ``deviation`` is zero."""
        e = [d + g * self.grid.step + self.rounding for d, g in zip(self.deviation, self.steps)]
        if not any(e):
            return 0.0
        return math.nextafter(math.sqrt(sum(x * x for x in e)) * (1 + 4 * 2.0**-53), math.inf)

    @property
    def holds_true(self) -> bool:
        """Whether the stored C-obstacle provably holds the true one (no false free)."""
        s = Fraction(self.grid.step)
        return all(g * s >= Fraction(d) + Fraction(self.rounding)
                   for d, g in zip(self.deviation, self.steps))

    def __repr__(self) -> str:
        dev = [f"{d:.3g}" for d in self.deviation]
        return (f"Margin(steps={list(self.steps)}, deviation={dev}, "
                f"error_bound={self.error_bound:.3g})")
