"""Scenes: scene files, what each body becomes and why (the scene model), the C-space, the cache.

- :mod:`.scene` — :class:`~cspace.scene.scene.Body`, :class:`~cspace.scene.scene.Scene`;
- :mod:`.files` — :func:`~cspace.scene.files.load_scene` (and :func:`~cspace.scene.files.save_scene`): our TOML, OMPL.app ``.cfg``, Parasol ``.env``;
- :mod:`.classify` — the classification rules (convex / solid / surface / dropped, with the reason);
- :mod:`.build` — building the C-obstacles, locally or on an executor;
- :mod:`.model` — :func:`~cspace.scene.model.model_scene` → :class:`~cspace.scene.model.SceneModel`,
  and :class:`~cspace.scene.model.CSpace`, the C-obstacles of a scene with its queries;
- :mod:`.cache` — the content-addressed disk cache of C-obstacles.
"""

from .files import load_scene, save_scene
from .model import CSpace, SceneModel, model_scene
from .scene import Body, Scene

__all__ = ["Body", "Scene", "load_scene", "save_scene", "CSpace", "SceneModel", "model_scene"]
