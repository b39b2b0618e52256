"""docs/cli.md: every subcommand's options with unit, range or choices and default, generated from
the parser and the rules behind each option's ``type=`` (:mod:`cobra_ref.infra.validation`).

``python -m cobra_ref.cli.options_doc`` rewrites docs/cli.md (or the file given as its argument);
``tests/test_inputs.py`` checks that the committed file is ``cli_markdown()``.
"""

from __future__ import annotations

import argparse
import os
import re

from ..infra.rule import is_number, number_text

CLI_DOC = os.path.join("docs", "cli.md")  # relative to the repository's root
_UNIT_IN_HELP = re.compile(r"\[([^\]]+)\]")
_DEFAULT_IN_HELP = re.compile(r"\(default:? ([^;)]+)")
HEADER = """# The `cobra-ref` command's options

Generated from the command's parser and the rules of `cobra_ref.infra.validation`; do not edit by
hand: `python -m cobra_ref.cli.options_doc` rewrites this file (a test checks that it is current).
`cobra-ref COMMAND --help` says what each option does; a value outside its range is refused with a
message that names the option, the value, the allowed range and the unit.
"""


def _allowed_and_unit(action) -> tuple[str, str]:
    """(unit, range or choices) of an option that is not a flag."""
    rule_ = getattr(action.type, "rule", None)
    if rule_ is not None:
        return rule_.unit, rule_.range_text()
    if action.choices is not None:
        return "-", ", ".join(map(str, action.choices))
    found = _UNIT_IN_HELP.search(action.help or "")
    return (found.group(1) if found else "-"), getattr(action.type, "allowed", None) or _describe_type(action)


def _option_rows(parser) -> list[tuple]:
    """(option, unit, range or choices, default) of every option of ``parser``."""
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        name = ", ".join(action.option_strings) or action.metavar or action.dest
        if isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction)):
            rows.append((name, "-", "flag", "off"))
            continue
        unit, allowed = _allowed_and_unit(action)
        if action.required:
            default = "required"
        elif isinstance(action, argparse._AppendAction):
            allowed += " (repeatable)"
            default = "none" if not action.default else str(action.default)
        elif action.default is None:
            found = _DEFAULT_IN_HELP.search(action.help or "")
            default = found.group(1) if found else "-"
        else:
            default = number_text(action.default) if is_number(action.default) else str(action.default)
        rows.append((name, unit if unit not in ("", "-") else "-", allowed, default))
    return rows


def _describe_type(action) -> str:
    """What an option without a rule takes: a file, an integer, a finite number, text."""
    metavar = str(action.metavar or "")
    name = getattr(action.type, "__name__", "")
    if action.type is int:
        return "integer"
    if action.type is float:
        return "number"
    if name == "finite_float":
        return "finite number"
    if name == "pixels":
        return "whole number of pixels"
    if "FILE" in metavar.upper() or "." in metavar or action.dest in ("out", "json", "cache", "run"):
        return "file path"
    if metavar:
        return metavar
    return "text"


def options_markdown(parser=None) -> str:
    """Every subcommand's option table (markdown) with unit, range or choices and default, from
    the rules behind each option's ``type=``; ``parser`` defaults to ``cobra-ref``'s."""
    if parser is None:
        from . import build_parser

        parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    lines = []
    for command, p in sub.choices.items():
        rows = _option_rows(p)
        lines.append(f"## `cobra-ref {command}`" + ("" if rows else ": no options"))
        lines.append("")
        if rows:
            lines.append("| option | unit | allowed | default |")
            lines.append("|---|---|---|---|")
            for name, unit, allowed, default in rows:
                cells = (f"`{name}`", unit, allowed, default)
                lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
            lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def cli_markdown(parser=None) -> str:
    """The text of docs/cli.md: a header that says how it is made, then ``options_markdown``."""
    return HEADER + "\n" + options_markdown(parser)


def write_cli_doc(path: str = CLI_DOC) -> str:
    """Write ``cli_markdown()`` to ``path`` (atomically); return the path."""
    from ..infra.output import write_text

    write_text(path, cli_markdown())
    return path


if __name__ == "__main__":  # python -m cobra_ref.cli.options_doc [docs/cli.md]
    import argparse

    cli = argparse.ArgumentParser(prog="python -m cobra_ref.cli.options_doc",
                                  description="Write the option tables of every cobra-ref subcommand (docs/cli.md).")
    cli.add_argument("targets", nargs="*", default=[CLI_DOC], metavar="FILE", help=f"where to write (default {CLI_DOC})")
    for target in cli.parse_args().targets:
        print(f"wrote {write_cli_doc(target)}")
