"""A Sphinx extension: ``reference/cli.md`` written from ``cspace``'s argument parser at
build time, so that the CLI reference never drifts from ``cspace --help``."""

from __future__ import annotations

import argparse
from pathlib import Path


def _parser() -> argparse.ArgumentParser:
    """The parser ``cspace.cli.main`` builds, caught before it parses anything."""
    import cspace.cli as cli

    caught = {}

    class _Stop(Exception):
        pass

    def grab(self, args=None, namespace=None):
        caught["parser"] = self
        raise _Stop

    old = argparse.ArgumentParser.parse_args
    argparse.ArgumentParser.parse_args = grab
    try:
        cli.main(["--help"])
    except _Stop:
        pass
    finally:
        argparse.ArgumentParser.parse_args = old
    return caught["parser"]


def write_cli_reference(app) -> None:
    import os

    # argparse wraps to the terminal's width: one width, so the page does not depend on it
    old, os.environ["COLUMNS"] = os.environ.get("COLUMNS"), "100"
    try:
        _write(app)
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def _write(app) -> None:
    parser = _parser()
    lines = ["# Command-line reference", "",
             "Generated from `cspace`'s argument parser when the docs are built: the same text "
             "as `cspace <command> --help`.", "", "```text", parser.format_help().rstrip(), "```", ""]
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, p in sub.choices.items():
        lines += [f"## cspace {name}", "", "```text", p.format_help().rstrip(), "```", ""]
    out = Path(app.srcdir) / "reference" / "cli.md"
    text = "\n".join(lines)
    if not out.exists() or out.read_text() != text:
        out.write_text(text)


def setup(app):
    app.connect("builder-inited", write_cli_reference)
    return {"parallel_read_safe": True}
