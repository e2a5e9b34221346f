"""``ego report``: one self-contained HTML file from the folder of ``ego compare``, ``ego
sweep`` or ``ego falsify`` (docs/report.md).

What it reads (nothing else): ``metrics.csv``, ``metrics_units.csv`` and ``compare.json`` (compare), or
``results.parquet`` (sweep; with ``falsified.md``: falsify); the PNG plots
in the folder; the recordings (``.rrd``) under it. What it writes: a verdict table per
scenario x controller x requirement (runs passed and failed, the worst robustness with its
unit, collisions), every run's metrics, the plots inline (base64 PNG and an inline SVG of
every run's robustness), for every failing run the ``ego run`` command that reproduces it
(:func:`ego.runner.run_command`), and relative links to the recordings. No script, no
external URL: the file opens the same offline, mailed or archived.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ego.params import ConfigError
from ego.results.summary import FIRST_VIOLATION_PREFIX, REQUIREMENTS_PREFIX

#: the marker of a file ``ego report`` wrote (another file is replaced only with --force)
GENERATOR = "ego report"
EXPECTED = (
    "expected the --out folder of ego compare (metrics.csv), ego sweep (results.parquet) or "
    "ego falsify (results.parquet and falsified.md)"
)
#: columns that are no metric of a run (text, bookkeeping)
_NOT_METRICS = {
    "run_id",
    "scenario",
    "controller",
    "seed",
    "status",
    "status_detail",
    "error",
    "collision_with",
    "backend",
    "lane_choice",
    "target_side",
    "host",
    "node",
    "attempts",
    "optimizer",
    "optimizer_seed",
    "wall_time",
}


@dataclass
class Campaign:
    """A results folder read back: its kind, scenario, rows (one dict per run) and what the
    rows' columns mean."""

    folder: Path
    kind: str  #: compare | sweep | falsify
    scenario: str
    rows: list[dict]
    params: list[str]  #: the columns that are a run's --set values
    units: dict[str, str] = field(default_factory=dict)
    formulas: dict[str, str | None] = field(default_factory=dict)  #: requirement -> formula (None: not stored)
    notes: list[str] = field(default_factory=list)
    fixed: dict = field(default_factory=dict)  #: --set values every run shares (compare.json)

    @property
    def requirements(self) -> list[str]:
        names: dict[str, None] = {}
        for r in self.rows:
            names.update((k[len(REQUIREMENTS_PREFIX) :], None) for k in r if k.startswith(REQUIREMENTS_PREFIX))
        return list(names)

    def robustness(self, row: dict, name: str) -> float | None:
        return _number(row.get(REQUIREMENTS_PREFIX + name))

    def violated_at(self, row: dict, name: str) -> float | None:
        """The first time ``name`` is violated in ``row``'s run (s); None where the run passed
        it or its folder does not store the time (written before ego kept it)."""
        return _number(row.get(FIRST_VIOLATION_PREFIX + name))

    @property
    def stores_times(self) -> bool:
        return any(k.startswith(FIRST_VIOLATION_PREFIX) for r in self.rows for k in r)

    def failures(self, row: dict) -> list[str]:
        """Why ``row`` fails: each violated requirement (robustness < 0) and a collision."""
        bad = [n for n in self.requirements if (v := self.robustness(row, n)) is not None and v < 0.0]
        return bad + (["collision"] if _true(row.get("collision")) else [])

    def command(self, row: dict) -> str:
        """The ``ego run`` command that makes ``row``'s run again."""
        from ego.requirements import defaults
        from ego.runner import run_command

        controller, params = str(row["controller"]), dict(self.fixed)
        if self.kind == "compare" and "@" in controller:  # a variant label: pid@kp_lat=0.02
            from ego.compare import parse_variant
            from ego.scenarios import scenario_class

            controller, variant = parse_variant(controller, scenario_class(self.scenario).task)
            params.update(variant)
        for p in self.params:
            if row.get(p) is not None and not (isinstance(row[p], float) and math.isnan(row[p])):
                params[p] = _plain(row[p])
        base = defaults(self.scenario)
        require = [(n, f) for n, f in self.formulas.items() if f is not None and base.get(n) != f]
        return run_command(self.scenario, controller, int(row["seed"]), params, require)

    def recording(self, row: dict) -> Path | None:
        """The run's recording in the folder, if it is there."""
        if self.kind == "compare":
            from ego.compare import file_label

            name = f"{file_label(str(row['controller']))}-seed{int(row['seed'])}.rrd"
        else:
            name = f"{row['controller']}-{row.get('run_id')}.rrd"
        path = self.folder / "runs" / name
        return path if path.is_file() else None


def _number(v: Any) -> float | None:
    if v is None or isinstance(v, bool):
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(x) else x


def _true(v: Any) -> bool:
    return v is True or str(v) == "True"


def _plain(v: Any) -> Any:
    """A stored value as ``--set`` takes it: 25.0 -> 25."""
    if isinstance(v, float) and v.is_integer():
        return int(v)
    return v


def _csv_value(text: str) -> Any:
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    try:
        return float(text)
    except ValueError:
        return text


def load(folder: str | Path) -> Campaign:
    """Read a results folder; ConfigError (one line naming it) when it is none."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ConfigError(f"bad DIR {str(folder)!r}: no such folder ({EXPECTED})")
    if (folder / "results.parquet").is_file():  # an interrupted sweep has no summary.md yet
        return _load_parquet(folder, "falsify" if (folder / "falsified.md").is_file() else "sweep")
    if (folder / "metrics.csv").is_file():
        return _load_compare(folder)
    raise ConfigError(f"bad DIR {str(folder)!r}: {EXPECTED}")


def _load_compare(folder: Path) -> Campaign:
    try:
        with open(folder / "metrics.csv", newline="") as f:
            rows = [{k: _csv_value(v) for k, v in r.items()} for r in csv.DictReader(f)]
        units = {}
        if (folder / "metrics_units.csv").is_file():
            with open(folder / "metrics_units.csv", newline="") as f:
                units = {r["metric"]: r["unit"] for r in csv.DictReader(f)}
    except (OSError, csv.Error, UnicodeDecodeError, KeyError) as exc:
        raise ConfigError(f"bad DIR {str(folder)!r}: cannot read its metrics.csv ({exc}; {EXPECTED})") from None
    if not rows or not {"controller", "seed", "scenario"} <= set(rows[0]):
        raise ConfigError(f"bad DIR {str(folder)!r}: its metrics.csv has no runs of ego compare ({EXPECTED})")
    c = Campaign(folder, "compare", str(rows[0]["scenario"]), rows, [], units)
    settings = _compare_settings(folder)
    if settings is None:  # written before ego compare kept compare.json
        c.notes.append(
            "This folder has no compare.json (an older ego compare): add the --set values the "
            "comparison was run with to each command."
        )
    else:
        c.fixed = dict(settings.get("set") or {})
        c.formulas.update(settings.get("requirements") or {})
        if settings.get("backend", "sumo") != "sumo":
            c.notes.append(f"The runs used --backend {settings['backend']}: add it to each command.")
    _requirements(c)
    return c


def _compare_settings(folder: Path) -> dict | None:
    import json

    from ego.compare import SETTINGS_FILE

    try:
        settings = json.loads((folder / SETTINGS_FILE).read_text())
    except (OSError, ValueError):
        return None
    return settings if isinstance(settings, dict) else None


def _load_parquet(folder: Path, kind: str) -> Campaign:
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(folder / "results.parquet")
    except Exception as exc:  # noqa: BLE001 - any unreadable file: one line
        raise ConfigError(
            f"bad DIR {str(folder)!r}: cannot read results.parquet ({type(exc).__name__}; {EXPECTED})"
        ) from None
    names = table.column_names
    if not {"run_id", "scenario", "controller", "seed", "status"} <= set(names) or table.num_rows == 0:
        raise ConfigError(f"bad DIR {str(folder)!r}: its results.parquet has no runs ({EXPECTED})")
    rows = table.to_pylist()
    # a row is run_id, scenario, controller, seed, its --set values, then status and the metrics
    params = names[names.index("seed") + 1 : names.index("status")]
    c = Campaign(folder, kind, str(rows[0]["scenario"]), rows, params)
    if kind == "falsify":
        md = (folder / "falsified.md").read_text(errors="replace")
        m = re.search(r"^Requirement: `([^:`]+): ([^`]+)`", md, re.M)
        if m:
            c.formulas[m.group(1)] = m.group(2)
    _requirements(c)
    return c


def _requirements(c: Campaign) -> None:
    """The formula of each requirement (the scenario's defaults unless the folder says) and
    the unit of its robustness."""
    from ego.requirements import defaults

    base = defaults(c.scenario)
    for n in c.requirements:
        c.formulas.setdefault(n, base.get(n))
    unknown = [n for n, f in c.formulas.items() if f is None]
    if unknown:
        c.notes.append(
            f"The formulas of {', '.join(unknown)} are not stored in the folder (a spec's "
            "[requirements]): add them to the commands with --require."
        )
    missing = [n for n in c.requirements if not c.units.get(REQUIREMENTS_PREFIX + n)]
    if missing:
        c.units.update({REQUIREMENTS_PREFIX + n: u for n, u in _requirement_units(c).items()})
    if c.kind != "compare":
        from ego.sweep.report import _unit

        for k in c.rows[0]:
            if (
                k not in c.units
                and k not in _NOT_METRICS
                and not k.startswith((REQUIREMENTS_PREFIX, FIRST_VIOLATION_PREFIX))
            ):
                try:
                    c.units[k] = _unit(c.scenario, k)
                except Exception:  # noqa: BLE001 - an undeclared column: no unit
                    c.units[k] = ""


def _requirement_units(c: Campaign) -> dict[str, str]:
    from ego.runner import RunSpec, requirements_of, resolve

    texts = {n: f for n, f in c.formulas.items() if f}
    try:
        row = c.rows[0]
        resolved = resolve(RunSpec(c.scenario, str(row["controller"]).partition("@")[0], 0, {}, requirements=texts))
        return {r.name: r.unit for r in requirements_of(resolved)}
    except Exception:  # noqa: BLE001 - a unit is a label: without one the table still holds
        return {}


# -- the HTML ------------------------------------------------------------------------------------


def _e(v: Any) -> str:
    return html.escape(str(v), quote=True)


def _fmt(v: Any) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _with_unit(name: str, unit: str | None) -> str:
    return name if not unit or unit in ("-", "mixed") else f"{name} [{unit}]"


def _table(head: list[str], body: list[list[str]], cls: str = "") -> str:
    """Cells are HTML already."""
    h = "".join(f"<th>{c}</th>" for c in head)
    rows = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in body)
    return f'<table class="{cls}"><thead><tr>{h}</tr></thead><tbody>{rows}</tbody></table>'


def verdicts(c: Campaign) -> list[dict]:
    """One entry per scenario x controller x requirement: runs, passed, failed, worst
    robustness, the earliest first violation (s; None: none, or not stored) and the
    collisions among those runs."""
    out = []
    controllers = list(dict.fromkeys(str(r["controller"]) for r in c.rows))
    for ctl in controllers:
        rows = [r for r in c.rows if str(r["controller"]) == ctl]
        for n in c.requirements:
            values = [v for r in rows if (v := c.robustness(r, n)) is not None]
            out.append(
                {
                    "scenario": c.scenario,
                    "controller": ctl,
                    "requirement": n,
                    "runs": len(values),
                    "passed": sum(v >= 0.0 for v in values),
                    "failed": sum(v < 0.0 for v in values),
                    "worst": min(values) if values else None,
                    "first_violation": min(
                        (t for r in rows if (t := c.violated_at(r, n)) is not None),
                        default=None,
                    ),
                    "collisions": sum(_true(r.get("collision")) for r in rows),
                }
            )
    return out


def _robustness_svg(c: Campaign) -> str:
    """Every run's robustness per requirement and controller, as an inline SVG (matplotlib)."""
    from ego.plots import pyplot

    plt = pyplot()  # the Agg backend: no display needed
    reqs = c.requirements
    if not reqs:
        return ""
    controllers = list(dict.fromkeys(str(r["controller"]) for r in c.rows))
    fig, axes = plt.subplots(1, len(reqs), figsize=(max(4.0, 2.6 * len(reqs)), 3.2), squeeze=False)
    for ax, n in zip(axes[0], reqs, strict=True):
        for i, ctl in enumerate(controllers):
            ys = [v for r in c.rows if str(r["controller"]) == ctl and (v := c.robustness(r, n)) is not None]
            ax.scatter([i] * len(ys), ys, s=14, c=["#d62728" if y < 0 else "#2ca02c" for y in ys])
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(range(len(controllers)), controllers, rotation=30, fontsize=7)
        ax.set_title(n, fontsize=8)
        ax.set_ylabel(_with_unit("robustness", c.units.get(REQUIREMENTS_PREFIX + n)), fontsize=7)
        ax.tick_params(labelsize=7)
    fig.suptitle("robustness of every run (below 0: violated)", fontsize=9)
    fig.tight_layout()
    buf = io.StringIO()
    fig.savefig(buf, format="svg")
    plt.close(fig)
    svg = buf.getvalue()
    return svg[svg.index("<svg") :]


def render(c: Campaign, out: Path) -> str:
    """The report of ``c`` as one HTML document; links are relative to ``out``'s folder: the
    header, then each section in turn."""
    base = out.resolve().parent
    parts = _header(c)
    for section in (_verdicts, _failing, _every_run, _plots, _recordings):
        parts += section(c, base)
    return _page(f"ego {c.kind}: {c.scenario}", "\n".join(parts))


def _header(c: Campaign) -> list[str]:
    """The title, the folder, the values every run shares and the campaign's notes."""
    reqs = c.requirements
    parts = [
        f"<h1>ego {c.kind}: {_e(c.scenario)}</h1>",
        f"<p>Folder <code>{_e(c.folder)}</code>: {len(c.rows)} runs, {len(reqs)} requirements. "
        "A requirement passes where its robustness is 0 or more.</p>",
    ]
    if c.fixed:
        shared = " ".join(f"--set {k}={v}" for k, v in c.fixed.items())
        parts.append(f"<p>Every run: <code>{_e(shared)}</code>.</p>")
    parts += [f'<p class="note">{_e(n)}</p>' for n in c.notes]
    return parts


def _verdicts(c: Campaign, base: Path) -> list[str]:
    """Per scenario, controller and requirement: runs, passed, failed, the worst
    robustness, the first violation; the formulas."""
    parts: list[str] = []
    body = []
    for v in verdicts(c):
        unit = c.units.get(REQUIREMENTS_PREFIX + v["requirement"], "")
        worst = "-" if v["worst"] is None else f"{v['worst']:.4g}" + ("" if unit in ("", "-", "mixed") else f" {unit}")
        cls = "fail" if v["failed"] else "pass"
        body.append(
            [
                _e(v["scenario"]),
                _e(v["controller"]),
                f'<span title="{_e(c.formulas.get(v["requirement"]) or "")}">{_e(v["requirement"])}</span>',
                str(v["runs"]),
                f'<span class="pass">{v["passed"]}</span>',
                f'<span class="{cls}">{v["failed"]}</span>',
                _e(worst),
                "-" if v["first_violation"] is None else f"{v['first_violation']:.2f}",
                str(v["collisions"]),
            ]
        )
    parts.append('<h2 id="verdicts">Verdicts</h2>')
    parts.append(
        _table(
            [
                "scenario",
                "controller",
                "requirement",
                "runs",
                "passed",
                "failed",
                "worst robustness",
                "first violation [s]",
                "collisions",
            ],
            body,
            "verdicts",
        )
    )
    parts.append(
        "<p>First violation: the earliest time, over the failing runs, at which the requirement "
        "is first violated (each failing run's own below).</p>"
        if c.stores_times
        else "<p>First violation: this folder keeps each run's robustness, not the time (written "
        "before ego stored it); the run's command below prints it (<code>requirement ... "
        "violated</code> event).</p>"
    )
    formulas = "".join(
        f"<li><code>{_e(n)}: {_e(f or '(formula not stored)')}</code></li>" for n, f in c.formulas.items()
    )
    parts.append(f"<ul>{formulas}</ul>")
    return parts


def _failing(c: Campaign, base: Path) -> list[str]:
    """Each failing run: why, from when, its recording and the command that reproduces it."""
    parts: list[str] = []
    failing = [(i, r) for i, r in enumerate(c.rows) if c.failures(r)]
    parts.append(f'<h2 id="failing">Failing runs ({len(failing)} of {len(c.rows)})</h2>')
    if failing:
        items = []
        for i, r in failing:
            rec = c.recording(r)
            link = f' <a href="{_e(os.path.relpath(rec, base))}">recording</a>' if rec else ""
            why = [f"{n} (from {t:.2f} s)" if (t := c.violated_at(r, n)) is not None else n for n in c.failures(r)]
            items.append(
                f'<li id="run-{i}">run {i} ({_e(r["controller"])}, seed {_e(_plain(r["seed"]))}): '
                f'{_e(", ".join(why))}{link}<pre class="cmd">{_e(c.command(r))}</pre></li>'
            )
        parts.append(f'<ul class="failing">{"".join(items)}</ul>')
    else:
        parts.append("<p>None: every run passed every requirement without a collision.</p>")
    return parts


def _every_run(c: Campaign, base: Path) -> list[str]:
    """Every run: its parameters, status, verdict, each requirement's robustness and each
    metric."""
    parts: list[str] = []
    metrics = [
        k
        for k in dict.fromkeys(k for r in c.rows for k in r)
        if k not in _NOT_METRICS and k not in c.params and not k.startswith(REQUIREMENTS_PREFIX)
        if not k.startswith(FIRST_VIOLATION_PREFIX)
        if any(_number(r.get(k)) is not None or isinstance(r.get(k), bool) for r in c.rows)
    ]
    head = ["run", "controller", "seed", *map(_e, c.params), "status", "verdict"]
    head += [_e(_with_unit(n, c.units.get(REQUIREMENTS_PREFIX + n))) for n in c.requirements]
    head += [_e(_with_unit(m, c.units.get(m))) for m in metrics] + ["recording"]
    body = []
    for i, r in enumerate(c.rows):
        bad = c.failures(r)
        rec = c.recording(r)
        verdict = f'<a class="fail" href="#run-{i}">fail</a>' if bad else '<span class="pass">pass</span>'
        body.append(
            [str(i), _e(r["controller"]), _e(_plain(r["seed"])), *(_e(_fmt(r.get(p))) for p in c.params)]
            + [_e(r.get("status")), verdict]
            + [_e(_fmt(c.robustness(r, n))) for n in c.requirements]
            + [_e(_fmt(r.get(m))) for m in metrics]
            + [f'<a href="{_e(os.path.relpath(rec, base))}">.rrd</a>' if rec else "-"]
        )
    parts.append('<h2 id="runs">Every run</h2>')
    parts.append(f'<div class="scroll">{_table(head, body, "runs")}</div>')
    return parts


def _plots(c: Campaign, base: Path) -> list[str]:
    """The robustness plot and the folder's PNG plots, inline."""
    parts: list[str] = []
    parts.append('<h2 id="plots">Plots</h2>')
    svg = _robustness_svg(c)
    if svg:
        parts.append(f'<figure class="plot">{svg}</figure>')
    for png in sorted(c.folder.glob("*.png")):
        data = base64.b64encode(png.read_bytes()).decode()
        parts.append(
            f'<figure class="plot"><img alt="{_e(png.name)}" src="data:image/png;base64,{data}">'
            f"<figcaption>{_e(png.name)}</figcaption></figure>"
        )
    return parts


def _recordings(c: Campaign, base: Path) -> list[str]:
    """Links to the folder's recordings."""
    parts: list[str] = []
    recs = sorted(c.folder.rglob("*.rrd"))
    parts.append(f'<h2 id="recordings">Recordings ({len(recs)})</h2>')
    if recs:
        links = "".join(
            f'<li><a href="{_e(os.path.relpath(p, base))}">{_e(p.relative_to(c.folder))}</a></li>' for p in recs
        )
        parts.append(f"<p>Open one with <code>rerun FILE.rrd</code>.</p><ul>{links}</ul>")
    else:
        parts.append("<p>None in the folder.</p>")
    return parts


_STYLE = """
body{font-family:sans-serif;margin:1.5em;color:#222;background:#fff}
table{border-collapse:collapse;margin:.5em 0;font-size:13px}
th,td{border:1px solid #bbb;padding:2px 6px;text-align:right}
th{background:#eee}td:nth-child(-n+3){text-align:left}
.pass{color:#1a7f1a;font-weight:bold}.fail{color:#c01818;font-weight:bold}
.note{background:#fff6d5;padding:4px}pre.cmd{background:#f4f4f4;padding:4px;white-space:pre-wrap}
figure.plot img,figure.plot svg{max-width:100%;height:auto}div.scroll{overflow-x:auto}
"""


def _page(title: str, body: str) -> str:
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f'<meta name="generator" content="{GENERATOR}"><title>{_e(title)}</title>'
        f"<style>{_STYLE}</style></head>\n<body>\n{body}\n</body></html>\n"
    )


def check_out(out: Path, force: bool) -> None:
    """``out`` may be written: a new file, one ``ego report`` wrote, or any with ``force``."""
    from ego.checks import check_generated

    check_generated(out, force, ".html", f'content="{GENERATOR}"', "ego report")


def write(folder: str | Path, out: str | Path | None = None, force: bool = False) -> tuple[Campaign, Path]:
    """Read ``folder``, write its report to ``out`` (default ``folder/report.html``)."""
    from ego.outputs import write_generated

    campaign = load(folder)
    path = Path(out) if out is not None else Path(folder) / "report.html"
    check_out(path, force)
    write_generated(path, render(campaign, path))
    return campaign, path
