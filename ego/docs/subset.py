"""The supported-subset table of docs/openscenario.md, generated from the element registry
(:mod:`ego.openscenario.registry`) beside the reference player's (esmini) own published
coverage (``esmini_coverage.toml``, its source URL and commit inside).

    python -m ego.docs openscenario-table [--check]

It rewrites the controller-properties table too (between ``<!-- generated:controller-properties
-->`` and its end marker). The table sits between ``<!-- generated:openscenario-subset -->`` and
``<!-- /generated:openscenario-subset -->``; ``--check`` compares instead of writing and exits
1 when the page is not what the registry makes (``tests/test_docs.py`` runs the check).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from ego.docs.common import ROOT

PAGE = ROOT / "docs" / "openscenario.md"
COVERAGE = Path(__file__).with_name("esmini_coverage.toml")
START, END = "<!-- generated:openscenario-subset -->", "<!-- /generated:openscenario-subset -->"


def esmini() -> dict:
    """The recorded coverage: ``source``, ``commit`` and ``elements`` (tag -> status)."""
    with open(COVERAGE, "rb") as f:
        return tomllib.load(f)


def esmini_cell(tags: tuple[str, ...], coverage: dict[str, str]) -> str:
    """The esmini column of a row about ``tags``: the first element's status, then each
    other element whose status differs (an element esmini's file does not name: not listed)."""
    status = [coverage.get(t, "not listed") for t in tags]
    head = status[0]
    rest = [f"`{t}` {s}" for t, s in zip(tags[1:], status[1:]) if s != head]
    return "; ".join([head, *rest])


def table() -> str:
    """The generated block (markers included)."""
    from ego.openscenario import loader  # noqa: F401 - declares every element
    from ego.openscenario.registry import table_rows

    data = esmini()
    cov = data["elements"]
    lines = [
        START,
        "",
        f"The esmini column is the reference player's own published coverage ([osc_coverage.txt]({data['source']}),"
        f" commit {data['commit'][:10]}), per element; generated with `python -m ego.docs openscenario-table` from"
        " ego's element registry (`ego/openscenario/registry.py`).",
        "",
        "| element | ego | esmini | notes and deviations |",
        "|---|---|---|---|",
    ]
    deviations = []
    for label, supported, note, tags in table_rows():
        lines.append(f"| {label} | {supported} | {esmini_cell(tags, cov)} | {note} |")
        if "deviation" in note.lower():
            deviations.append(f"`{tags[0]}`")
    lines += [
        "",
        "Where ego deviates from the standard (each row's note says how and why): " + ", ".join(deviations) + ".",
        "",
        END,
    ]
    return "\n".join(lines)


#: the controller-properties table's markers (:mod:`ego.openscenario.controller_properties`)
PROPS_START, PROPS_END = "<!-- generated:controller-properties -->", "<!-- /generated:controller-properties -->"


def properties_table() -> str:
    """The generated block of controller properties as ego parameters (markers included)."""
    from ego.openscenario.controller_properties import markdown_table

    return "\n".join(
        [
            PROPS_START,
            "",
            "Generated with `python -m ego.docs openscenario-table` from `MAPPED` and `NOT_USED` in"
            " `ego/openscenario/controller_properties.py`; the controller kinds are the reference player's"
            " (its `ControllerACC`, `ControllerALKS`, `ControllerALKS_R157SM`...). A property of another"
            " kind's controller, or one not listed, is read and not used.",
            "",
            markdown_table(),
            "",
            PROPS_END,
        ]
    )


def _replace(text: str, start: str, end: str, block: str) -> str:
    i, j = text.find(start), text.find(end)
    if i < 0 or j < i:
        raise KeyError(f"no block {start} ... {end} in {PAGE}")
    return text[:i] + block + text[j + len(end) :]


def regenerate(check: bool) -> bool:
    """Write the tables into the page (or, ``check``, only compare); True when they were current."""
    text = PAGE.read_text()
    new = _replace(text, START, END, table())
    new = _replace(new, PROPS_START, PROPS_END, properties_table())
    if new != text and not check:
        from ego.outputs import write_text

        write_text(PAGE, new)
    return new == text
