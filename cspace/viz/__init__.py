"""Drawing scenes in meshcat: :class:`SceneView`, offline HTML, screenshots in headless Chromium.

- :mod:`.scene_view` — :class:`~cspace.viz.scene_view.SceneView` (meshes, paths, animation, framing);
- :mod:`.draw` — :func:`~cspace.viz.draw.draw_scene` (a whole scene, as modelled);
- :mod:`.browser` — :func:`~cspace.viz.browser.find_chromium`, :func:`~cspace.viz.browser.screenshot`.

meshcat is imported only when a view is made.
"""

from .browser import find_chromium, screenshot
from .draw import draw_scene
from .scene_view import SceneView

__all__ = ["SceneView", "draw_scene", "find_chromium", "screenshot"]
