"""Sphinx: the CLI reference, the ``--help`` of ``eqrec`` and of each of its commands, run when the site is built.

``.. eqrec-cli-help::`` with no argument prints ``eqrec --help``; with a command name (``design``) that command's
``--help``.  ``.. eqrec-cli-commands::`` lists the commands the parser has, so a new command shows up, and the
build fails (:func:`check_every_command_documented`) while the page has no ``eqrec-cli-help`` for it.
"""
from __future__ import annotations

import os
import subprocess
import sys

from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.errors import ExtensionError


def _commands() -> list[str]:
    from eqrec.cli import _parser

    parser = _parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return list(sub.choices)


def _help(command: str | None) -> str:
    args = [sys.executable, "-m", "eqrec", *([command] if command else []), "--help"]
    env = {**os.environ, "COLUMNS": "100"}
    out = subprocess.run(args, capture_output=True, text=True, env=env, timeout=120)
    if out.returncode != 0:
        raise ExtensionError(f"{' '.join(args[2:])} failed (exit {out.returncode}): {out.stderr[-2000:]}")
    return out.stdout


class CliHelp(Directive):
    optional_arguments = 1

    def run(self):
        command = self.arguments[0] if self.arguments else None
        env = self.state.document.settings.env
        env.metadata[env.docname].setdefault("eqrec_cli", []).append(command or "")
        text = _help(command)
        title = f"eqrec {command} --help" if command else "eqrec --help"
        block = nodes.literal_block(text, text, language="text")
        return [nodes.rubric(title, title), block]


class CliCommands(Directive):
    def run(self):
        items = nodes.bullet_list()
        for name in _commands():
            para = nodes.paragraph()
            para += nodes.literal(f"eqrec {name}", f"eqrec {name}")
            items += nodes.list_item("", para)
        return [items]


def check_every_command_documented(app, env):
    documented = {c for meta in env.metadata.values() for c in meta.get("eqrec_cli", [])}
    if not documented:
        return
    missing = [c for c in _commands() if c not in documented]
    if missing:
        raise ExtensionError(f"the CLI reference has no eqrec-cli-help for the command(s) {missing}")


def setup(app):
    app.add_directive("eqrec-cli-help", CliHelp)
    app.add_directive("eqrec-cli-commands", CliCommands)
    app.connect("env-updated", check_every_command_documented)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
