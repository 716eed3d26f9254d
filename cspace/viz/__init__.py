"""Drawing scenes in meshcat: :class:`SceneView`, offline HTML, screenshots in headless Chromium.

- :mod:`.scene_view` — :class:`~cspace.viz.scene_view.SceneView` and :func:`~cspace.viz.scene_view.draw_scene`;
- :mod:`.browser` — :func:`~cspace.viz.browser.find_chromium`, :func:`~cspace.viz.browser.screenshot`.

meshcat is imported only when a view is made.
"""

from .browser import find_chromium, screenshot
from .scene_view import SceneView, draw_scene

__all__ = ["SceneView", "draw_scene", "find_chromium", "screenshot"]
