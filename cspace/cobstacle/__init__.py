"""C-obstacles ``CO = O ⊕ (−R)`` and their exact queries over translations.

- :mod:`.obstacle` — :class:`~cspace.cobstacle.obstacle.CSpaceObstacle`: one C-obstacle, built
  once (convex, mesh, or grown mesh sum), queried many times;
- :mod:`.convex` — the convex C-obstacle's queries; :mod:`.union` a union of engines, not built;
- :mod:`.pairs` — triangle pairs and containment terms (an open body, or a non-convex robot
  part), their operands shared by content in :mod:`.pair_sides`; :mod:`.surface` — one hull
  per triangle of an open body, their reference;
- :mod:`.margin` — :class:`~cspace.cobstacle.margin.Margin`, the outward rounding that makes a
  stored C-obstacle hold the true one (no false free).

The C-space of a scene (:class:`cspace.CSpace`, all its C-obstacles behind one set of queries) is
made from a scene (``CSpace.from_scene`` models it first), so it lives one layer up, in
:mod:`cspace.scene.model`.
"""

from .margin import Margin
from .obstacle import CSpaceObstacle

__all__ = ["CSpaceObstacle", "Margin"]
