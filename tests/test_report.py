"""``ego report``: real folders of real small runs (one sweep with a collision, one compare,
one falsification), the HTML read back with html.parser; a headless Chromium screenshot
under the ``browser`` marker (``pytest -m browser tests/test_report.py``)."""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest

from ego.cli import main

pytestmark = pytest.mark.sumo

# a lead braking at 9 m/s^2 half a second in: 5 m behind it the ego collides, 40 m behind it
# it stops in time (the evasion off)
SWEEP = """
scenario = "emergency-brake"
controllers = ["pid"]
seeds = 1
[set]
evade = false
ego_speed = 20
lead_speed = -1
lead_final_speed = 0
lead_brake_time = 0.5
duration = 3
traffic_density = 0
lead_decel = 9
[grid]
lead_gap = [5, 40]
"""
FALSIFY = """
scenario = "emergency-brake"
controllers = ["pid"]
requirement = "keep_30m"
seed = 0
budget = 2
[requirements]
keep_30m = "always (gap_front >= 30 m)"
[set]
duration = 3
traffic_density = 0
[search]
lead_gap = [5, 25]
"""


class Page(HTMLParser):
    """What a test asks of the HTML: every src/href, the tables' rows, the commands."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.links: list[str] = []
        self.rows: list[list[str]] = []
        self.commands: list[str] = []
        self.tags: list[str] = []
        self.text = text
        self._cell: list[str] | None = None
        self._row: list[str] | None = None
        self._pre = False
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        for k, v in attrs:
            if k in ("src", "href"):
                self.links.append(v or "")
        if tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "pre":
            self._pre, self._text = True, []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._row is not None and self._cell is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.rows.append(self._row)
            self._row = None
        elif tag == "pre":
            self._pre = False
            self.commands.append("".join(self._text))

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)
        if self._pre:
            self._text.append(data)


def _made(base: Path, name: str, argv: list[str], status: int) -> Path:
    """``base/name``: the folder ``ego ARGV --out base/name`` writes, and its report."""
    out = base / name
    assert main([*argv, "--out", str(out)]) == status
    assert main(["report", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    base = tmp_path_factory.mktemp("report")
    (base / "sweep.toml").write_text(SWEEP)
    (base / "falsify.toml").write_text(FALSIFY)
    return base


@pytest.fixture(scope="module")
def sweep_dir(base):
    return _made(base, "sweep", ["sweep", str(base / "sweep.toml"), "--jobs", "2"], 0)


@pytest.fixture(scope="module")
def falsify_dir(base):  # status 1: a violation found
    argv = ["falsify", str(base / "falsify.toml"), "--optimizer", "random", "--no-verify", "--jobs", "2"]
    return _made(base, "falsify", argv, 1)


@pytest.fixture(scope="module")
def cmp_dir(base):
    return _made(base, "cmp", ["compare", "emergency-brake", "--controllers", "pid", "--set", "duration=3"], 0)


@pytest.fixture
def folders(request):
    """The folder a test parametrised by ``name`` reads."""
    return request.getfixturevalue(f"{request.node.callspec.params['name']}_dir").parent


def page(folder: Path) -> Page:
    return Page((folder / "report.html").read_text())


@pytest.mark.parametrize("name", ["sweep", "falsify", "cmp"])
def test_the_report_is_self_contained_and_holds_every_run(folders, name):
    import pyarrow.parquet as pq

    p = page(folders / name)
    # no script at all, nothing fetched: every src/href is inline data, an anchor or a relative file
    assert "script" not in p.tags
    for link in p.links:
        assert link.startswith(("data:image/png;base64,", "#", "runs/")), link
    assert "svg" in p.tags  # the robustness plot, inline
    if name == "cmp":
        n = 1
    else:
        n = pq.read_table(folders / name / "results.parquet").num_rows
    runs = [r for r in p.rows if r and r[0].isdigit()]
    assert [r[0] for r in runs] == [str(i) for i in range(n)]
    verdicts = [r for r in p.rows if r and r[0] == "emergency-brake"]
    assert verdicts and all(len(r) == 9 for r in verdicts)


def test_sweep_verdicts_count_the_collision_and_name_the_unit(sweep_dir):
    folders = sweep_dir.parent
    p = page(folders / "sweep")
    table = {r[2]: r for r in p.rows if r and r[0] == "emergency-brake"}
    # no_collision: 2 runs, 1 passed, 1 failed, worst robustness -1 (a boolean), 1 collision
    assert table["no_collision"][3:6] == ["2", "1", "1"]
    assert table["no_collision"][6] == "-1 bool" and table["no_collision"][8] == "1"
    assert table["stays_in_lane"][6].endswith(" m")
    # the failing run's recording is linked, relative to the report
    rrd = [link for link in p.links if link.endswith(".rrd")]
    assert rrd and all((folders / "sweep" / link).is_file() for link in rrd)


def test_every_failing_run_has_its_command_and_it_reproduces_the_verdict(sweep_dir):
    folders = sweep_dir.parent
    import pyarrow.parquet as pq

    rows = pq.read_table(folders / "sweep" / "results.parquet").to_pylist()
    failing = [r for r in rows if r["requirements.no_collision"] < 0]
    p = page(folders / "sweep")
    assert len(p.commands) == len(failing) == 1
    cmd = p.commands[0]
    assert cmd.startswith("ego run emergency-brake -c pid --seed 0 ") and "--set lead_gap=5" in cmd
    args = shlex.split(cmd)[2:] + ["--json"]
    proc = subprocess.run([sys.executable, "-m", "ego", "run", *args], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1, proc.stderr[-2000:]  # the collision again
    out = json.loads(proc.stdout)
    for name, value in out["requirements"].items():
        assert value == pytest.approx(failing[0][f"requirements.{name}"], abs=1e-6), name
    # the first violation's time: stored in the row, shown in the verdicts and the failing run,
    # the time of the run's own requirement event
    hit = failing[0]["first_violation.no_collision"]
    events = [e["t"] for e in out["events"] if e["kind"] == "requirement" and " no_collision " in e["text"]]
    assert events and hit == pytest.approx(events[0], abs=1e-6)
    verdict = {r[2]: r for r in p.rows if r and r[0] == "emergency-brake"}["no_collision"]
    assert verdict[7] == f"{hit:.2f}"
    assert f"no_collision (from {hit:.2f} s)" in p.text


def test_falsify_commands_carry_the_spec_requirement(falsify_dir):
    p = page(falsify_dir)
    assert p.commands and all("--require 'keep_30m: always (gap_front >= 30 m)'" in c for c in p.commands)


def test_compare_commands_carry_its_set_values(cmp_dir):
    from ego.report import load

    c = load(cmp_dir)
    assert c.command(c.rows[0]) == "ego run emergency-brake -c pid --seed 0 --set duration=3"
    # a folder of an older ego compare (no compare.json): said, not guessed
    (cmp_dir / "compare.json").rename(cmp_dir / "compare.json.bak")
    try:
        old = load(cmp_dir)
        assert old.command(old.rows[0]) == "ego run emergency-brake -c pid --seed 0"
        assert any("no compare.json" in n for n in old.notes)
    finally:
        (cmp_dir / "compare.json.bak").rename(cmp_dir / "compare.json")
    assert any(link == "runs/pid-seed0.rrd" for link in page(cmp_dir).links)


def test_a_compare_variant_label_becomes_its_set_values(cmp_dir):
    from ego.report import load

    c = load(cmp_dir)
    row = {**c.rows[0], "controller": "pid@kp_lat=0.02"}
    assert c.command(row) == "ego run emergency-brake -c pid --seed 0 --set duration=3 --set kp_lat=0.02"


def test_out_elsewhere_links_relative_to_it_and_a_foreign_file_is_kept(sweep_dir, tmp_path, capsys):
    folders = sweep_dir.parent
    out = tmp_path / "sub" / "r.html"
    assert main(["report", str(folders / "sweep"), "--out", str(out)]) == 0
    for link in page_links(out):
        if link.endswith(".rrd"):
            assert (out.parent / link).resolve().is_file()
    mine = tmp_path / "mine.html"
    mine.write_text("<html>my notes</html>")
    assert main(["report", str(folders / "sweep"), "--out", str(mine)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "ego report did not write it" in err and "--force" in err
    assert mine.read_text() == "<html>my notes</html>"
    assert main(["report", str(folders / "sweep"), "--out", str(mine), "--force"]) == 0
    assert main(["report", str(folders / "sweep"), "--out", str(mine)]) == 0  # its own file: replaced


def page_links(path: Path) -> list[str]:
    return Page(path.read_text()).links


def _files(folder: Path, **files: str) -> Path:
    for name, text in files.items():
        (folder / name.replace("_", ".")).write_text(text)
    return folder


@pytest.mark.parametrize(
    "make, expected",
    [
        (lambda d: d / "missing", "no such folder"),
        (lambda d: d, "expected the --out folder of ego compare"),
        (lambda d: _files(d, metrics_csv="a,b\n1,2\n"), "has no runs of ego compare"),
        (lambda d: _files(d, results_parquet="not parquet", summary_md=""), "cannot read results.parquet"),
    ],
)
def test_bad_dir_is_one_line_exit_2_nothing_written(tmp_path, capsys, make, expected):
    folder = make(tmp_path)
    before = sorted(os.listdir(tmp_path))
    assert main(["report", str(folder)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ego: error: bad DIR") and expected in err, err
    assert sorted(os.listdir(tmp_path)) == before


def test_bad_out_is_refused(sweep_dir, tmp_path, capsys):
    folders = sweep_dir.parent
    assert main(["report", str(folders / "sweep"), "--out", str(tmp_path / "r.txt")]) == 2
    assert "expected a file ending in .html" in capsys.readouterr().err
    assert not (tmp_path / "r.txt").exists()


# -- a real browser ----------------------------------------------------------------------------


CHROMIUM = next((p for n in ("chromium", "chromium-browser", "google-chrome") if (p := shutil.which(n))), None)


def chromium() -> str:
    assert CHROMIUM is not None
    return CHROMIUM


@pytest.mark.browser
@pytest.mark.skipif(CHROMIUM is None, reason="needs Chromium, an optional system package (apt-get install chromium)")
@pytest.mark.parametrize("name", ["sweep", "cmp"])
def test_headless_chromium_draws_the_report_without_console_errors(folders, tmp_path, name):
    import numpy as np
    from PIL import Image

    html_file = (folders / name / "report.html").resolve()
    png = tmp_path / "shot.png"
    common = ["--headless", "--no-sandbox", "--disable-gpu", f"--user-data-dir={tmp_path / 'profile'}"]
    env = {**os.environ, "HOME": str(tmp_path)}
    shot = subprocess.run(
        [chromium(), *common, f"--screenshot={png}", "--window-size=1280,2000", "--enable-logging=stderr", "--v=0"]
        + [html_file.as_uri()],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert shot.returncode == 0, shot.stderr[-2000:]
    console = [ln for ln in shot.stderr.splitlines() if "CONSOLE" in ln or "Uncaught" in ln]
    assert not console, console
    pixels = np.asarray(Image.open(png).convert("L"), dtype=float)
    assert pixels.shape == (2000, 1280)
    assert pixels.std() > 10  # text, tables and plots, not a blank page
    # the top band (title and verdict table) is drawn too, not only the plots below
    assert pixels[:300].std() > 10
    dom = subprocess.run(
        [chromium(), *common, "--dump-dom", html_file.as_uri()], capture_output=True, text=True, timeout=120, env=env
    )
    assert dom.returncode == 0 and 'id="verdicts"' in dom.stdout and "<svg" in dom.stdout
