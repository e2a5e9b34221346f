"""docs/ cannot drift from the code: result rows regenerate, every table has its block, every
link resolves."""

import re
from pathlib import Path

import pytest

from ego import docs

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted({t.page for t in docs.tables()})

#: a few rows of every results page, chosen cheap (seconds of simulation each); each row is
#: computed from its own runs only, so it must equal the committed line
ROWS = [
    ("traffic", "pid"),
    ("cut-in", "pid"),
    ("bare-model", "fuzzy"),
    ("sine", "rbf-smc"),
    ("curve", "narma-l2"),
    ("curve-speeds", "pid"),
    ("curve-variations", "pid, pedal=true"),
    ("lane-centering", "report 003's, lateral-error"),
    ("recovery", "25 m/s"),
    ("platoon", "pid, 0-2"),
    ("followers", "pid, f3"),
    ("headway", "2"),
    ("scale-model", "pid, lambda 0.2 s"),
    ("ccrb", "pid"),
    ("ccrs-ttc1", "fuzzy"),
    ("cross-emergency-brake", "pid"),
    # the RL baselines: a controller row (the trained rows take minutes of training each)
    ("rl-curve", "pid"),
    ("xosc-equivalence", "emergency_brake.xosc / emergency-brake, pid"),
    ("falsify-surrogate", "cma"),  # the analytic stand-in: no SUMO, seconds
    ("curved-lane-keeping", "left-1000, 130 km/h, pid"),
    ("curved-cut-in", "left-250, pid"),
    ("alks-concrete", "alks_4_4_cut_in / pid"),
    ("alks-concrete", "alks_4_4_cut_in / careful-driver"),
    ("alks-4-6-forward-range", "pid"),
]
TABLES = {t.name: t for t in docs.tables()}


def committed(table: docs.Table) -> str:
    return docs.block(docs.page_path(table.page).read_text(), table.name)


def test_every_page_has_a_checked_row():
    assert {TABLES[name].page for name, _ in ROWS} == set(PAGES)


@pytest.mark.parametrize("name", list(TABLES))
def test_every_table_has_its_block_with_its_command_and_header(name):
    table = TABLES[name]
    text = committed(table)
    assert f"Table: `python -m ego.docs results --table {name}`" in text
    assert all(f"`{c}`" in text for c in table.commands)
    lines = text.splitlines()
    assert docs._line(table.header) in lines
    # one line per row, in order, and nothing else between header and notes
    rows = [ln for ln in lines if ln.startswith("| ")][1:]
    assert [r.split(" | ")[0][2:] for r in rows] == [r.label for r in table.rows]


@pytest.fixture(scope="module")
def results():
    jobs = [j for name, label in ROWS for j in TABLES[name].row(label).jobs]
    return docs.run_jobs(jobs, workers=2, progress=False)


@pytest.mark.sumo
@pytest.mark.parametrize("name,label", ROWS, ids=[f"{n}:{lab}" for n, lab in ROWS])
def test_a_row_regenerates_as_committed(results, name, label):
    table = TABLES[name]
    line = docs.render_row(table.row(label), results)
    assert line in committed(table).splitlines()


def test_no_wall_time_in_the_results():
    for page in PAGES:
        assert "wall_time" not in docs.page_path(page).read_text()


LINK = re.compile(r"\]\(([^)\s]+)\)")


def _markdown_files():
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def anchors(path: Path) -> set[str]:
    """The anchors GitHub makes for a markdown file: its headings' slugs and explicit ids."""
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.S)
    slugs = {
        re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in re.findall(r"^#+ (.+)$", text, flags=re.M)
    }
    return slugs | set(re.findall(r'<a id="([^"]+)">', text))


@pytest.mark.parametrize("path", _markdown_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_resolves(path):
    """Every link to a file in the repository points at one that exists, and an anchor at a
    heading of it. README and docs link pages that other branches add (gym.md, traces.md,
    ...): this test passes once they are merged."""
    missing = []
    for target in LINK.findall(path.read_text()):
        if re.match(r"[a-z]+:", target):
            continue
        file, _, anchor = target.partition("#")
        dest = (path.parent / file) if file else path
        if not dest.exists() or anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            missing.append(target)
    assert not missing, f"{path.relative_to(ROOT)} has links to nothing: {missing}"


def test_a_bad_page_or_table_is_one_line_and_exit_2(capsys):
    assert docs.main(["results", "--page", "nope"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("python -m ego.docs: error: unknown page 'nope' (known: ") and "\n" not in err
    assert docs.main(["results", "--table", "nope"]) == 2


def test_the_openscenario_subset_table_is_the_registrys(capsys):
    """docs/openscenario.md's supported-subset table is what the element registry makes
    (``python -m ego.docs openscenario-table`` rewrites it), beside esmini's recorded coverage."""
    from ego.docs import subset

    assert docs.main(["openscenario-table", "--check"]) == 0, "run: python -m ego.docs openscenario-table"
    assert "is the registry's" in capsys.readouterr().out
    data = subset.esmini()
    assert re.fullmatch(r"[0-9a-f]{40}", data["commit"]) and data["commit"] in data["source"]
    assert subset.esmini_cell(("SpeedAction",), data["elements"]) == "yes"
    assert subset.esmini_cell(("CatalogLocations", "MiscObjectCatalog"), data["elements"]) == (
        "yes; `MiscObjectCatalog` no"
    )
    assert subset.esmini_cell(("License",), data["elements"]) == "not listed"
