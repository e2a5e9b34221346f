"""The one summary formatter: per-controller markdown tables over many runs.

``ego compare`` writes ``metrics.md`` (:func:`comparison`: runs by status, then each
headline metric as mean +- standard deviation over seeds) and ``ego sweep`` writes
``summary.md`` (:func:`sweep`: runs by status, then each headline metric's median and
percentiles). Both are built from :func:`table`, one row per controller and one cell
function per column, over the runs' flattened metrics.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ego.results.metrics import headline_names, metric_units, with_unit
from ego.results.trace import Metric

#: the flattened metrics of a run's requirements: ``requirements.<name>`` (robustness)
REQUIREMENTS_PREFIX = "requirements."
#: the flattened metrics of the first time each requirement is violated (s): ``first_violation.<name>``
FIRST_VIOLATION_PREFIX = "first_violation."
#: one run's flattened metrics (status and error among them)
Row = Mapping[str, Any]


def table_row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def table(
    controllers: Sequence[str],
    runs: Mapping[str, Sequence[Row]],
    columns: Sequence[tuple[str, Callable[[Sequence[Row]], str]]],
) -> list[str]:
    """A markdown table: the header (``controller`` then each column's name), the rule, and
    one line per controller whose cells are each column's function of its runs."""
    lines = [table_row(["controller"] + [name for name, _ in columns]), "|---|" + "---|" * len(columns)]
    for c in controllers:
        mine = runs.get(c, ())
        lines.append(table_row([c] + [cell(mine) for _, cell in columns]))
    return lines


def _finite(values: Sequence[Any]) -> list[float]:
    return [
        float(v)
        for v in values
        if isinstance(v, (int, float)) and not isinstance(v, bool) and v is not None and math.isfinite(v)
    ]


def mean_spread(values: Sequence[Any]) -> str:
    """``mean +- sd`` of the finite numbers, ``(k/n)`` when only k of n runs have one;
    ``k/n`` for a yes/no metric (k runs say yes); ``-`` when none has a number."""
    if values and all(isinstance(v, bool) for v in values):
        return f"{sum(values)}/{len(values)}"
    nums = _finite(values)
    if not nums:
        return "-"
    mean = float(np.mean(nums))
    text = f"{mean:.3g}"
    if len(nums) > 1:
        spread = float(np.std(nums, ddof=1))
        text += f" +- {0.0 if spread < 1e-9 * max(1.0, abs(mean)) else spread:.2g}"
    if len(nums) < len(values):
        text += f" ({len(nums)}/{len(values)})"
    return text


def percentiles(values: Sequence[Any]) -> str:
    """``median [5th, 95th percentile] (min to max), n`` of the finite numbers, or ``-``."""
    nums = _finite(values)
    if not nums:
        return "-"
    a = np.array(nums)
    p5, p50, p95 = np.percentile(a, [5, 50, 95])
    return f"{p50:.3g} [{p5:.3g}, {p95:.3g}] ({a.min():.3g} to {a.max():.3g}), {a.size}"


def preventable_lines(by: Mapping[str, Sequence[Mapping[str, Any]]], controllers: Sequence[str]) -> list[str]:
    """Per controller, of its runs that computed ``collision_preventable`` (``--preventable``:
    the collisions), how many UN R157's careful driver avoids; nothing if none computed it."""
    if not any(m.get("collision_preventable") is not None for ms in by.values() for m in ms):
        return []
    lines = ["", "Collisions UN R157's careful driver avoids on the same scenario (`collision_preventable`):", ""]
    for c in controllers:
        k = sum(1 for m in by.get(c, ()) if m.get("collision_preventable") is True)
        n = sum(1 for m in by.get(c, ()) if m.get("collision_preventable") is not None)
        lines.append(f"- {c}: {k} of {n}")
    return lines


def requirement_lines(groups: Mapping[str, Sequence[Mapping[str, Any]]]) -> list[str]:
    """A markdown table of passes and failures per requirement (columns) and group (rows:
    e.g. controllers), from flattened metric rows (``requirements.<name>`` robustness); no
    lines when no row has a requirement."""
    names = list(
        dict.fromkeys(
            k[len(REQUIREMENTS_PREFIX) :]
            for rows in groups.values()
            for r in rows
            for k in r
            if k.startswith(REQUIREMENTS_PREFIX)
        )
    )
    if not names:
        return []
    lines = [
        "",
        "Requirements (robustness >= 0: passed; passed/evaluated, the smallest robustness in brackets):",
        "",
        "| | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for group, rows in groups.items():
        cells = []
        for n in names:
            values = _finite([r.get(REQUIREMENTS_PREFIX + n) for r in rows])
            passed = sum(v >= 0.0 for v in values)
            cells.append(f"{passed}/{len(values)} ({min(values):.3g})" if values else "-")
        lines.append(f"| {group} | " + " | ".join(cells) + " |")
    return lines


def _by_controller(rows: Sequence[Row], controllers: Sequence[str]) -> dict[str, list[Row]]:
    runs: dict[str, list[Row]] = {c: [] for c in controllers}
    for r in rows:
        runs.setdefault(r["controller"], []).append(r)
    return runs


def comparison(scenario: str, rows: Sequence[Row], controllers: Sequence[str], declared: Sequence[Metric]) -> str:
    """``ego compare``'s metrics.md. ``rows``: each run's metrics with ``controller``,
    ``seed``, ``status`` and ``error``."""
    present = headline_names(declared, (n for r in rows for n in r["metrics"]))
    units = metric_units(declared, present)

    def statuses(mine: Sequence[Row]) -> str:
        counts: dict[str, int] = {}
        for r in mine:
            counts[r["status"]] = counts.get(r["status"], 0) + 1
        return ", ".join(f"{n} {s}" for s, n in counts.items())

    def metric(key: str) -> Callable[[Sequence[Row]], str]:
        return lambda mine: mean_spread([r["metrics"].get(key) for r in mine])

    columns = [("runs", statuses)] + [(with_unit(k, units[k]), metric(k)) for k in present]
    lines = [
        f"# {scenario}: {len(rows)} runs",
        "",
        "Mean +- standard deviation over seeds; (k/n) when only k of n runs have the value; "
        "k/n for a yes/no metric: k of n runs say yes.",
        "",
        *table(controllers, _by_controller(rows, controllers), columns),
    ]
    by = {c: [r["metrics"] for r in mine] for c, mine in _by_controller(rows, controllers).items()}
    lines += preventable_lines(by, controllers)
    lines += requirement_lines(by)
    errors = [r for r in rows if r["error"]]
    if errors:
        lines += ["", "Errors:", ""] + [f"- {r['controller']} seed {r['seed']}: {r['error']}" for r in errors]
    unfinished = [r for r in rows if r["status"] == "interrupted"]
    if unfinished:
        lines += [
            "",
            f"Interrupted: {len(unfinished)} of {len(rows)} runs did not finish: "
            + ", ".join(f"{r['controller']} seed {r['seed']}" for r in unfinished[:20])
            + (", ..." if len(unfinished) > 20 else ""),
        ]
    return "\n".join(lines) + "\n"


def sweep(
    scenario: str,
    source: str,
    swept: Sequence[str],
    seeds: int,
    rows: Sequence[Row],
    controllers: Sequence[str],
    declared: Sequence[Metric],
) -> str:
    """``ego sweep``'s summary.md. ``rows``: each run's flattened metrics with
    ``controller``, ``seed``, ``status`` and ``error`` beside them."""
    heads = [m for m in declared if m.headline and not m.name.endswith(".")]
    names = {k for r in rows for k in r}
    heads = [m for m in heads if m.name in names]
    runs = _by_controller(rows, controllers)
    lines = [
        f"# {scenario} sweep: {len(rows)} runs",
        "",
        f"Spec: `{source}`; swept: {', '.join(swept) or 'nothing'}; {seeds} seed(s).",
        "",
    ]
    statuses = sorted({r["status"] for r in rows})

    def count(status: str) -> Callable[[Sequence[Row]], str]:
        return lambda mine: str(sum(1 for r in mine if r["status"] == status))

    lines += table(controllers, runs, [("runs", lambda mine: str(len(mine)))] + [(s, count(s)) for s in statuses])
    if heads:

        def metric(key: str) -> Callable[[Sequence[Row]], str]:
            return lambda mine: percentiles([r.get(key) for r in mine])

        lines += [
            "",
            "Headline metrics over the runs that have them: median [5th, 95th percentile] (min to max), n runs.",
            "",
            *table(controllers, runs, [(with_unit(m.name, m.unit), metric(m.name)) for m in heads]),
        ]
    for extra in ("collision_avoidable",):
        if extra in names:
            lines += [
                "",
                f"Collisions braking at the friction limit from the trigger would have avoided (`{extra}`):",
                "",
            ]
            for c in controllers:
                k = sum(1 for r in runs.get(c, ()) if r.get(extra) is True)
                lines.append(f"- {c}: {k}")
    lines += preventable_lines(runs, controllers)
    lines += requirement_lines(runs)
    errors = [r for r in rows if r["status"] == "error"]
    if errors:
        lines += [
            "",
            f"{len(errors)} runs ended in an error; the first:",
            "",
            f"- {errors[0]['controller']} seed {errors[0]['seed']}: {errors[0]['error']}",
        ]
    return "\n".join(lines) + "\n"
