"""The site's generated references, made from the built program at build time so they cannot drift.

Three directives, each writing what it read into the build folder's `_generated/` as well (which
tests/docs/docs_test.py compares with the program once more):

    ```{dqj-parameter-table}
    ```      every key of `dqjulia schema`: type, allowed values, default and meaning
    ```{dqj-cli-reference}
    ```      `dqjulia --help` and each subcommand's `--help`, a section a subcommand
    ```{dqj-c-api}
    ```      core/include/dqjulia/dqjulia.h: its comments as text, its declarations as code

The program is the configuration value `dqj_cli` (`-D dqj_cli=build/bin/dqjulia`, or the
environment's DQJ_CLI); without it the build fails with a message saying so.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
from pathlib import Path

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.errors import ExtensionError
from sphinx.util.docutils import SphinxDirective

HEADER = Path(__file__).resolve().parents[2] / "core" / "include" / "dqjulia" / "dqjulia.h"


def run_cli(app: Sphinx, *args: str) -> str:
    """The program's standard output for `args`; an error naming the command if it fails."""
    cli = app.config.dqj_cli or os.environ.get("DQJ_CLI", "")
    if not cli:
        raise ExtensionError("dqj_reference: no dqjulia program: build with -D dqj_cli=PATH or DQJ_CLI=PATH")
    try:
        done = subprocess.run([cli, *args], capture_output=True, text=True, check=False, timeout=60)
    except OSError as error:
        raise ExtensionError(f"dqj_reference: cannot run {cli}: {error}") from error
    if done.returncode != 0:
        raise ExtensionError(f"dqj_reference: `{cli} {' '.join(args)}` failed ({done.returncode}): {done.stderr}")
    return done.stdout


def keep(app: Sphinx, name: str, text: str) -> None:
    """Writes `text` to <outdir>/_generated/<name>, what the page was made from."""
    path = Path(app.outdir) / "_generated" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


def table(header: list[str], rows: list[list[nodes.Node]], widths: list[int]) -> nodes.table:
    """A docutils table of `rows` of cells (each a list of nodes)."""
    group = nodes.tgroup(cols=len(header))
    for width in widths:
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    head += nodes.row("", *[nodes.entry("", nodes.paragraph(text=title)) for title in header])
    group += head
    body = nodes.tbody()
    for cells in rows:
        body += nodes.row("", *[nodes.entry("", *cell) for cell in cells])
    group += body
    result = nodes.table()
    result += group
    return result


def literal(text: str) -> nodes.paragraph:
    return nodes.paragraph("", "", nodes.literal(text=text))


def number(value: float) -> str:
    """A limit as people write it: 15, 0.5, 1e9, 1e150."""
    if float(value).is_integer() and abs(value) < 1e7:
        return str(int(value))
    if 1e-4 <= abs(value) < 1e7:
        return repr(float(value))
    mantissa, exponent = format(float(value), ".15e").split("e")
    mantissa = mantissa.rstrip("0").rstrip(".")
    return "%se%d" % (mantissa, int(exponent))


def allowed(field: dict) -> str:
    """The values a key takes, from its type, range and choices."""
    parts = []
    if "choices" in field:
        parts.append(", ".join(choice["name"] for choice in field["choices"]))
    if "min" in field and "max" in field:
        low = "(" if field.get("min_exclusive") else "["
        high = ")" if field.get("max_exclusive") else "]"
        parts.append(f"{low}{number(field['min'])}, {number(field['max'])}{high}")
    if field.get("auto"):
        parts.append('or "auto"')
    if field.get("optional"):
        parts.append("may be absent")
    return " ".join(parts)


class ParameterTable(SphinxDirective):
    """Every key of the parameter file, from `dqjulia schema`."""

    def run(self) -> list[nodes.Node]:
        text = run_cli(self.env.app, "schema")
        keep(self.env.app, "schema.json", text)
        rows = []
        for field in json.loads(text)["fields"]:
            meaning = field["help"]
            if "choices" in field:
                meaning += ". " + "; ".join("%s: %s" % (choice["name"], choice["help"]) for choice in field["choices"])
            if field.get("animatable"):
                meaning += " (may be keyframed)"
            if field.get("image_only"):
                meaning += " (pictures only: a bake does not depend on it)"
            default = "" if "default" not in field else json.dumps(field["default"])
            rows.append(
                [
                    [literal(field["key"])],
                    [nodes.paragraph(text=field["type"])],
                    [nodes.paragraph(text=allowed(field))],
                    [literal(default)] if default else [],
                    [nodes.paragraph(text=f"{field['label']}: {meaning}")],
                ]
            )
        return [table(["key", "type", "values", "default", "meaning"], rows, [18, 10, 14, 18, 40])]


def subcommands(help_text: str) -> list[str]:
    """The subcommand names of `dqjulia --help` (CLI11's "Subcommands:" list)."""
    names, inside = [], False
    for line in help_text.splitlines():
        if line.startswith("Subcommands:"):
            inside = True
        elif inside and re.match(r"^  \S", line):
            names.append(line.split()[0])
    return names


class CliReference(SphinxDirective):
    """`dqjulia --help`, then a section with each subcommand's `--help`."""

    def section(self, title: str, ident: str, text: str) -> nodes.section:
        section = nodes.section(ids=[ident], names=[nodes.fully_normalize_name(ident)])
        section += nodes.title(text=title)
        section += nodes.literal_block(text, text, language="text")
        self.state.document.note_implicit_target(section, section)
        return section

    def run(self) -> list[nodes.Node]:
        app = self.env.app
        top = run_cli(app, "--help")
        keep(app, "cli/dqjulia.txt", top)
        result: list[nodes.Node] = [nodes.literal_block(top, top, language="text")]
        for name in subcommands(top):
            text = run_cli(app, name, "--help")
            keep(app, f"cli/{name}.txt", text)
            result.append(self.section(f"dqjulia {name}", f"dqjulia-{name}", text))
        return result


def header_items(text: str) -> list[tuple[str, str]]:
    """The header as ("title" | "prose" | "code", text) items: its comments become prose, a
    `/* ---- Title ---- */` comment a title, its declarations code (include guards and the
    extern "C" lines left out)."""
    skip = re.compile(
        r'^(#ifndef DQJULIA_H|#define DQJULIA_H|#endif|#ifdef __cplusplus|extern "C" \{|\}|#include .*)\s*$'
    )
    items: list[tuple[str, str]] = []
    lines = text.splitlines()
    index = 0

    def add(kind: str, chunk: str) -> None:
        if items and items[-1][0] == kind and kind == "code":
            items[-1] = (kind, items[-1][1] + "\n" + chunk)
        else:
            items.append((kind, chunk))

    while index < len(lines):
        line = lines[index]
        stripped = line.strip()
        if stripped.startswith("/*"):
            comment = [line]
            while "*/" not in comment[-1]:
                index += 1
                comment.append(lines[index])
            body = []
            for part in comment:
                bare = re.sub(r"^\s*/\*+ ?|\s*\*/\s*$", "", part)
                body.append(re.sub(r"^\s*\* ?", "", bare))
            title = re.match(r"^-+ (.*?) -+$", body[0].strip())
            if title:
                items.append(("title", title.group(1)))
                body = body[1:]
            prose = "\n".join(body).strip()
            if prose:
                items.append(("prose", prose))
        elif stripped and not skip.match(stripped):
            add("code", line)
        elif not stripped and items and items[-1][0] == "code":
            items.append(("gap", ""))
        index += 1
    return [item for item in items if item[0] != "gap"]


def inline(text: str) -> list[nodes.Node]:
    """Text with its `quoted` parts as code (the header's only markup)."""
    parts = text.split("`")
    if len(parts) % 2 == 0:  # an unpaired backquote: all text
        return [nodes.Text(text)]
    return [
        nodes.literal(text=part) if odd else nodes.Text(part)
        for odd, part in ((index % 2 == 1, part) for index, part in enumerate(parts))
        if part
    ]


def prose_nodes(text: str) -> list[nodes.Node]:
    """A comment's text as paragraphs, its "- " lines as a bullet list; indented lines (a
    table of arguments) kept as they are."""
    result: list[nodes.Node] = []
    for block in re.split(r"\n\s*\n", text):
        items: list[list[str]] = [[]]
        for line in block.splitlines():
            if line.startswith("- "):
                items.append([line[2:]])
            else:
                items[-1].append(line)
        lead = [line for line in items[0] if line.strip()]
        if any(line.startswith("  ") for line in lead[1:]):
            first, rest = lead[0], "\n".join(lead[1:])
            result.append(nodes.paragraph("", "", *inline(first)))
            result.append(nodes.literal_block(rest, rest, language="text"))
        elif lead:
            result.append(nodes.paragraph("", "", *inline(" ".join(line.strip() for line in lead))))
        if len(items) > 1:
            bullets = nodes.bullet_list()
            for item in items[1:]:
                bullets += nodes.list_item(
                    "", nodes.paragraph("", "", *inline(" ".join(line.strip() for line in item)))
                )
            result.append(bullets)
    return result


class CApi(SphinxDirective):
    """The C ABI from core/include/dqjulia/dqjulia.h: the header's own comments and declarations."""

    def run(self) -> list[nodes.Node]:
        self.env.note_dependency(str(HEADER))
        text = HEADER.read_text(encoding="utf-8")
        keep(self.env.app, "dqjulia.h", text)
        result: list[nodes.Node] = []
        section: nodes.section | None = None

        def put(*new: nodes.Node) -> None:
            if section is None:
                result.extend(new)
            else:
                section.extend(new)

        for kind, chunk in header_items(text):
            if kind == "title":
                ident = nodes.make_id("c-api-" + chunk)
                section = nodes.section(ids=[ident], names=[nodes.fully_normalize_name(chunk)])
                section += nodes.title(text=chunk)
                self.state.document.note_implicit_target(section, section)
                result.append(section)
            elif kind == "prose":
                put(*prose_nodes(chunk))
            else:
                put(nodes.literal_block(chunk, chunk, language="c"))
        return result


def setup(app: Sphinx) -> dict:
    app.add_config_value("dqj_cli", "", "env")
    app.add_directive("dqj-parameter-table", ParameterTable)
    app.add_directive("dqj-cli-reference", CliReference)
    app.add_directive("dqj-c-api", CApi)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
