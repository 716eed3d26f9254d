"""Headless Chromium for meshcat drawings: finding it, offline windows and screenshots.

:func:`find_chromium` locates a browser; :func:`screenshot` renders a saved HTML page to PNG;
:class:`_OfflineWindow` is a meshcat window that serves nothing (the scene is saved as HTML).
"""

from __future__ import annotations

import base64
import logging
import os
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path

__all__ = ["screenshot", "find_chromium"]


log = logging.getLogger(__name__)


# --------------------------------------------------------------------------------------
# meshcat without a server


class _OfflineWindow:
    """Stand-in for ``meshcat.visualizer.ViewerWindow`` that starts nothing.

    It records the commands in a scene tree as meshcat's zmq server does and produces the same
    self-contained HTML as ``Visualizer.static_html()`` (api-notes §3.1).
    """

    def __init__(self):
        from meshcat.servers.tree import SceneTree

        self.tree = SceneTree()
        self.web_url = None

    def send(self, command) -> None:
        import umsgpack
        from meshcat.servers.tree import SceneTree, find_node

        data = command.lower()
        kind = data["type"]
        path = [p for p in data["path"].split("/") if p]
        if kind == "delete":
            if not path:
                self.tree = SceneTree()
            else:
                parent = find_node(self.tree, path[:-1])
                if path[-1] in parent:
                    del parent[path[-1]]
            return
        packed = umsgpack.packb(data)
        node = find_node(self.tree, path)
        if kind == "set_object":
            node.object = packed
            node.properties = []
        elif kind == "set_transform":
            node.transform = packed
        elif kind == "set_property":
            node.properties.append(packed)
        elif kind == "set_animation":
            node.animation = packed
        else:  # capture_image and the like need a browser
            raise RuntimeError(
                f"meshcat command {kind!r} needs a live viewer (SceneView(live=True))"
            )

    def get_scene(self) -> str:
        import meshcat
        from meshcat.servers.tree import walk

        def create_command(blob: bytes) -> str:
            # As meshcat.servers.zmqserver.create_command (not imported: it pulls in tornado and
            # a pyzmq DeprecationWarning).
            data = base64.b64encode(blob).decode("ascii")
            return (
                f'\nfetch("data:application/octet-binary;base64,{data}")'
                "\n    .then(res => res.arrayBuffer())"
                "\n    .then(buffer => viewer.handle_command_bytearray(new Uint8Array(buffer)));\n"
            )

        cmds = []
        for node in walk(self.tree):
            blobs = [node.object] if node.object is not None else []
            blobs += list(node.properties)
            blobs += [node.transform] if node.transform is not None else []
            blobs += [node.animation] if node.animation is not None else []
            cmds.extend(create_command(b) for b in blobs)
        viewer_js = os.path.join(os.path.dirname(meshcat.__file__), "viewer", "dist", "main.min.js")
        with open(viewer_js, encoding="utf-8") as f:
            js = f.read()  # the three.js viewer bundle, inlined (~850 kB)
        return (
            "<!DOCTYPE html><html><head><meta charset=utf-8><title>MeshCat</title></head><body>"
            '<div id="meshcat-pane"></div><script>' + js + "</script><script>"
            'var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));'
            + "".join(cmds)
            + "</script><style>body {margin: 0; } #meshcat-pane { width: 100vw; height: 100vh; "
            "overflow: hidden; }</style></body></html>"
        )


def find_chromium() -> str | None:
    """The Chromium (or Chrome) executable to use, or None.

    ``$CSPACE_CHROMIUM`` if set (None if it is not an executable file), else the first of
    chromium, chromium-browser, google-chrome, google-chrome-stable on PATH, else
    ``/usr/bin/chromium`` if it exists.
    """
    env = os.environ.get("CSPACE_CHROMIUM")
    if env:
        return env if os.path.isfile(env) and os.access(env, os.X_OK) else None
    for exe in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        found = shutil.which(exe)
        if found:
            return found
    return "/usr/bin/chromium" if os.access("/usr/bin/chromium", os.X_OK) else None


def screenshot(html_path, png_path, *, size=(1024, 768), timeout: float = 60,
               virtual_time_budget: int | None = None, retries: int = 1) -> Path:
    """Render an HTML file (e.g. from :meth:`SceneView.save`) to a PNG with headless Chromium.

    Chromium runs with a throw-away profile, no sandbox (needed as root), no GPU (WebGL on
    SwiftShader, software; ``--enable-unsafe-swiftshader`` opts in, as Chromium now asks: only
    pass pages you trust, such as :meth:`SceneView.save` output) and no background networking,
    in its own process group so a hung run is killed whole.

    Parameters
    ----------
    html_path : path
        The page to render (opened as ``file://``).
    png_path : path
        Where to write the screenshot (parent folders are created).
    size : (int, int), default (1024, 768)
        Window width and height in pixels.
    timeout : float, default 60
        Seconds per attempt.
    virtual_time_budget : int or None, default None
        Milliseconds of virtual time the page gets before the shot, to let a playing animation
        advance. None (default): shoot once loaded, which already shows the whole scene. With
        a budget, 3 of 105 shots hung in our runs (Chromium 156, software WebGL); 0 of 96
        without.
    retries : int, default 1
        Extra attempts after a timeout (a headless run occasionally hangs).

    Returns
    -------
    Path
        ``png_path``.

    Raises
    ------
    RuntimeError
        If no Chromium is found (install it: ``apt-get install -y chromium`` on Debian), or
        it fails, times out on every attempt, or writes no PNG.
    """
    chrome = find_chromium()
    if chrome is None:
        raise RuntimeError(
            "Chromium not found: install it (Debian: apt-get install -y chromium) "
            "or set CSPACE_CHROMIUM to a Chromium/Chrome executable"
        )
    html_path, png_path = Path(html_path).resolve(), Path(png_path).resolve()
    if not html_path.is_file():
        raise FileNotFoundError(html_path)
    png_path.parent.mkdir(parents=True, exist_ok=True)
    width, height = (int(x) for x in size)
    last = ""
    for _attempt in range(1 + max(0, int(retries))):
        png_path.unlink(missing_ok=True)
        with tempfile.TemporaryDirectory(prefix="cspace-chromium-") as profile:
            cmd = [
                chrome, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--no-first-run", "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--hide-scrollbars", f"--user-data-dir={profile}",
                f"--window-size={width},{height}", f"--screenshot={png_path}",
            ]
            if virtual_time_budget is not None:
                cmd.append(f"--virtual-time-budget={int(virtual_time_budget)}")
            cmd.append(html_path.as_uri())
            proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                    start_new_session=True)
            try:
                _, err = proc.communicate(timeout=timeout)
            except subprocess.TimeoutExpired:
                _kill_group(proc)
                _, err = proc.communicate()
                last = f"timed out after {timeout} s; stderr: {_tail(err)}"
                log.warning("chromium screenshot of %s %s", html_path, last)
                continue
            finally:
                _kill_group(proc)  # the renderer and zygote children, if any outlived it
            if proc.returncode == 0 and png_path.is_file() and png_path.stat().st_size > 0:
                return png_path
            last = f"exit status {proc.returncode}; stderr: {_tail(err)}"
            break
    raise RuntimeError(f"Chromium screenshot of {html_path} failed ({last})")


def _tail(err: bytes | None, n: int = 5) -> str:
    lines = (err or b"").decode("utf-8", "replace").strip().splitlines()[-n:]
    return " | ".join(lines) or "(empty)"


def _kill_group(proc: subprocess.Popen) -> None:
    """Kill the process group Chromium was started in (ours alone: start_new_session)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    if proc.poll() is None:
        proc.wait()
