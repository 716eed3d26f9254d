"""The documentation's code runs: every ```python block of the guides (``docs/``), page by
page in one namespace, in a scratch folder beside the shipped scenes, and the ``cspace``
command lines of the getting-started page. ``make docs`` builds the site (warnings are
errors); this checks what a reader would copy."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md")
               if "_build" not in p.parts and p.parent.name != "benchmarks"
               and p.name != "cli.md")


def _blocks(page: Path, lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", page.read_text(), flags=re.S | re.M)


@pytest.mark.parametrize("page", [p for p in PAGES if _blocks(p, "python")],
                         ids=lambda p: str(p.relative_to(DOCS)))
def test_python_blocks_run(page, tmp_path):
    """A page's blocks in order, in one fresh interpreter (as a reader's: a Dask cluster a
    guide starts leaves nothing behind in the test process), in a scratch folder with the
    shipped scenes."""
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    (tmp_path / "out").mkdir()
    code = "\n".join(f"# --- {page.name}, block {k + 1}\n{block}"
                     for k, block in enumerate(_blocks(page, "python")))
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                       text=True, timeout=600,
                       env={**os.environ, "CSPACE_CACHE": str(tmp_path / "cache")})
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-3000:]


def test_getting_started_command_lines_run(tmp_path, monkeypatch):
    """The page's Python (it writes window.toml), then each ``cspace ...`` line as given."""
    page = DOCS / "getting-started.md"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__docs__"}
    for code in _blocks(page, "python"):
        exec(compile(code, page.name, "exec"), namespace)
    lines = [line.split("#")[0].strip() for block in _blocks(page, "sh")
             for line in block.splitlines() if line.startswith("cspace ")]
    assert len(lines) >= 3
    env = {**os.environ, "CSPACE_CACHE": str(tmp_path / "cache")}
    for line in lines:
        r = subprocess.run([sys.executable, "-m", "cspace", *line.split()[1:]],
                           capture_output=True, text=True, env=env, timeout=300)
        assert r.returncode == 0, (line, r.stdout[-1000:], r.stderr[-1000:])


def test_every_scene_file_key_is_in_the_reference_table():
    from cspace.scene import files

    text = (DOCS / "guides" / "scene-files.md").read_text()
    for table, keys in (("robot", files._ROBOT_KEYS), ("planning", files._PLANNING_KEYS),
                        ("obstacles", files._OBSTACLE_KEYS)):
        for key in keys:
            assert f"| `{table}.{key}` |" in text, f"{table}.{key}"
    for key in files._TOP_KEYS:
        assert f"`{key}`" in text or f"[{key}]" in text, key


def test_the_guarantees_and_the_toml_reference_are_one_click_from_the_index():
    index = (DOCS / "index.md").read_text()
    assert "(guides/guarantees.md)" in index and "(guides/scene-files.md)" in index


def test_the_readme_example_and_command_lines_run(tmp_path, monkeypatch):
    """The README's Python example (it plans and writes window.toml), then its command lines
    with the exit status each comment promises (3 where it says so, else 0)."""
    readme = ROOT / "README.md"
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    monkeypatch.chdir(tmp_path)
    env = {**os.environ, "CSPACE_CACHE": str(tmp_path / "cache")}
    monkeypatch.setenv("CSPACE_CACHE", env["CSPACE_CACHE"])
    [code] = _blocks(readme, "python")
    namespace: dict = {"__name__": "__docs__"}
    exec(compile(code, "README.md", "exec"), namespace)
    assert namespace["r"].solved and (tmp_path / "window.toml").exists()
    lines = [line for block in _blocks(readme, "sh") for line in block.splitlines()
             if line.startswith("cspace ")]
    assert len(lines) == 3
    for line in lines:
        command, _, comment = line.partition("#")
        want = 3 if "exit 3" in comment else 0
        r = subprocess.run([sys.executable, "-m", "cspace", *command.split()[1:]],
                           capture_output=True, text=True, env=env, timeout=300)
        assert r.returncode == want, (line, r.stdout[-1000:], r.stderr[-1000:])


def test_the_committed_cli_reference_is_the_parsers(tmp_path):
    """``docs/reference/cli.md`` (linked from the README) is what the docs build writes from
    the argument parser: regenerate it with ``make docs`` when the CLI changes."""
    sys.path.insert(0, str(DOCS))
    try:
        from cli_reference import write_cli_reference
    finally:
        sys.path.remove(str(DOCS))
    (tmp_path / "reference").mkdir()
    write_cli_reference(type("App", (), {"srcdir": str(tmp_path)})())
    assert (tmp_path / "reference" / "cli.md").read_text() == \
        (DOCS / "reference" / "cli.md").read_text()
