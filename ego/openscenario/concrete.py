"""A concrete scenario out of a logical one: one run's parameter values written into a copy of
its ``.xosc`` (issue 39, point 3).

A logical scenario is a file whose top-level ``ParameterDeclarations`` a run overrides (``ego
run --set``, a sweep's grid or a variation file's row, a falsified point). The concrete file
is the template with those declarations' ``value`` set to the run's values (every
constraint checked as ``ego run`` checks it), its road, catalog and other file references
rewritten relative to where the concrete file is written, so it stands alone beside the
files it names. Given back to ``ego run`` with the run's controller, seed and the settings
that are not the file's parameters (ego's own ``duration``, a controller's gains: printed as
the command), it makes the same run.

The XML is written from the parsed tree: the template's elements, attributes and their order
stay; its comments and layout do not (a comment at the top names the template and the
values).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

from ego.openscenario.xmltree import Node, ScenarioFileError

#: element -> its attribute that names a file or a folder (relative to the scenario file)
PATH_ATTRIBUTES = {"LogicFile": "filepath", "SceneGraphFile": "filepath", "File": "filepath", "Directory": "path"}
#: the first line of the header comment: a file that starts with it is one ``ego concrete`` wrote
GENERATOR = "concrete scenario written by ego concrete"


def split_values(template: str | os.PathLike, values: Mapping[str, object]) -> tuple[dict, dict]:
    """(the file's own parameters, the rest: ego's settings and a controller's) of ``values``."""
    from ego.openscenario.loader import declared_parameters

    declared = declared_parameters(template)
    return {k: v for k, v in values.items() if k in declared}, {k: v for k, v in values.items() if k not in declared}


def _text(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)  # 25.0: a double read back


def concrete_xml(template: str | os.PathLike, values: Mapping[str, object], out: str | os.PathLike) -> str:
    """The concrete file's text: ``template`` with its top-level parameters in ``values`` set
    (checked: the run's own ConfigError for a bad value, before anything is written) and its
    file references made relative to ``out``'s folder."""
    from ego.openscenario.expressions import ExpressionError, resolve
    from ego.openscenario.files import locate
    from ego.openscenario.loader import _declarations, load, read_tree

    template, out = Path(template), Path(out)
    load(template, values)  # every check ego run makes: types, constraints, elements, files
    root = read_tree(template)
    decls = root.child("ParameterDeclarations")
    resolved = {k: p.value for k, p in _declarations(template, decls, {}, values).items()}
    here = out.resolve().parent

    def rewrite(node: Node, top: bool) -> Node:
        attrs = dict(node.attrs)
        if top and node.tag == "ParameterDeclaration" and attrs.get("name") in values:
            attrs["value"] = _text(resolved[attrs["name"]])
        key = PATH_ATTRIBUTES.get(node.tag)
        if key and key in attrs:
            try:
                target = str(resolve(attrs[key], resolved))
            except ExpressionError as exc:
                raise ScenarioFileError(template, node.line, str(exc)) from None
            # where ego run finds it: the path as written, else a search folder (ego.openscenario.files)
            found, _ = locate(template, target, "file", folder=node.tag == "Directory", note=False)
            absolute = (found or template.parent / target).resolve()
            try:
                attrs[key] = os.path.relpath(absolute, here)
            except ValueError:  # another drive: the absolute path
                attrs[key] = str(absolute)
        kids = [rewrite(c, top and node.tag in ("OpenSCENARIO", "ParameterDeclarations")) for c in node.children]
        return Node(node.tag, attrs, node.line, kids)

    lines: list[str] = []

    def emit(node: Node, depth: int) -> None:
        pad = "  " * depth
        attrs = "".join(f" {k}={quoteattr(v)}" for k, v in node.attrs.items())
        if not node.children:
            lines.append(f"{pad}<{node.tag}{attrs}/>")
            return
        lines.append(f"{pad}<{node.tag}{attrs}>")
        for c in node.children:
            emit(c, depth + 1)
        lines.append(f"{pad}</{node.tag}>")

    emit(rewrite(root, True), 0)
    shown = ", ".join(f"{k}={_text(resolved[k])}" for k in values) or "the template's defaults"
    comment = f"{GENERATOR}\n     from {template.resolve()}\n     with {shown}"
    head = f'<?xml version="1.0" encoding="UTF-8"?>\n<!-- {escape(comment).replace("--", "- -")} -->\n'
    return head + "\n".join(lines) + "\n"


def check_out(out: Path, force: bool) -> None:
    """``out`` may be written: a new ``.xosc``, one ``ego concrete`` wrote, or any with ``force``."""
    from ego.checks import check_generated

    check_generated(out, force, ".xosc", GENERATOR, "ego concrete", head=512)


def write(
    template: str | os.PathLike, values: Mapping[str, object], out: str | os.PathLike, force: bool = False
) -> Path:
    """Write the concrete scenario of ``template`` with ``values`` (its own parameters only)
    to ``out``, atomically; nothing is written if a value or the file is refused."""
    from ego.outputs import write_generated

    path = Path(out)
    check_out(path, force)
    write_generated(path, concrete_xml(template, values, path))
    return path
