"""Checks against what shares nothing with us: FCL on the raw meshes.

- :mod:`.oracle` — :class:`~cspace.check.oracle.SceneOracle`, the independent oracle of a scene;
- :mod:`.cross_check` — :func:`~cspace.check.cross_check.cross_check` (a C-space's answers against
  the oracle), :func:`~cspace.check.cross_check.path_collisions`, pose checks for turning paths;
- :mod:`.fcl` — python-fcl wrappers (:class:`~cspace.check.fcl.FclOracle`) and the winding number.
"""

from .cross_check import (PoseCollider, co_collider, cross_check, path_collisions,
                          pose_path_collisions)
from .fcl import FclOracle, fcl_convex, winding_number
from .oracle import SceneOracle

__all__ = ["SceneOracle", "cross_check", "path_collisions", "pose_path_collisions",
           "PoseCollider", "co_collider", "FclOracle", "fcl_convex", "winding_number"]
