"""The supported-subset table of docs/openscenario.md, generated from the element registry
(:mod:`ego.openscenario.registry`) beside the reference player's (esmini) own published
coverage (``esmini_coverage.toml``, its source URL and commit inside).

    python -m ego.docs openscenario-table [--check]

The table sits between ``<!-- generated:openscenario-subset -->`` and
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


def regenerate(check: bool) -> bool:
    """Write the table into the page (or, ``check``, only compare); True when it was current."""
    text = PAGE.read_text()
    i, j = text.find(START), text.find(END)
    if i < 0 or j < i:
        raise KeyError(f"no block {START} ... {END} in {PAGE}")
    new = text[:i] + table() + text[j + len(END) :]
    if new != text and not check:
        from ego.outputs import write_text

        write_text(PAGE, new)
    return new == text
