"""``ego concrete``: one run of a logical scenario as a standalone concrete ``.xosc``
(:mod:`ego.openscenario.concrete`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ego.cli.common import add_path, add_set
from ego.params import ConfigError


def add_parser(sub) -> argparse.ArgumentParser:
    """Add the ``concrete`` subcommand to ``ego``'s subparsers."""
    con = sub.add_parser(
        "concrete",
        help="write one run of a logical .xosc (--set values, a sweep or falsify row) as a concrete .xosc",
        description="Write one run of a logical OpenSCENARIO scenario as a standalone concrete .xosc: "
        "the template with its parameters set to the run's values (checked as ego run checks them: "
        "types, value constraints), its road and catalog references rewritten relative to --out. "
        "The run is either the template with --set values, or a row of an ego sweep or ego falsify "
        "folder over an .xosc (--run RUN_ID; the ids are results.parquet's run_id column, also in "
        "ego report). It prints the ego run command that makes the same run from the new file "
        "(the controller, the seed, and the settings that are not the file's parameters).",
        epilog="Examples:\n"
        "  ego concrete scenarios/openscenario/emergency_brake.xosc --set LeadGap=18 --out eb-18.xosc\n"
        "  ego sweep spec.toml --out runs/sw && ego concrete runs/sw --run 3f2a9c0d1e4b5a67 --out row.xosc\n"
        "Exit status: 0 written; 2 bad input (a value the file refuses, an unknown run id, --out "
        "not an .xosc or a file ego concrete did not write), nothing written.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    con.add_argument("source", metavar="SOURCE", help="a logical .xosc, or the --out folder of ego sweep / ego falsify")
    con.add_argument("--out", required=True, metavar="FILE.xosc", help="the concrete file to write")
    con.add_argument("--run", default=None, metavar="RUN_ID", help="with a folder: the row to write (its run_id)")
    add_set(con, "with an .xosc: a parameter's value (repeatable); ego's own settings go to the printed command")
    con.add_argument("--force", action="store_true", help="replace --out even if ego concrete did not write it")
    add_path(con)
    return con


def _from_folder(folder: Path, run_id: str | None) -> tuple[str, str, int, dict]:
    """(template, controller, seed, values) of row ``run_id`` of a sweep or falsify folder."""
    from ego.report import load

    campaign = load(folder)
    if campaign.kind == "compare":
        raise ConfigError(f"bad SOURCE {str(folder)!r}: a compare folder runs one concrete scenario (use its file)")
    ids = [str(r.get("run_id")) for r in campaign.rows]
    if run_id is None:
        raise ConfigError(
            f"a folder needs --run RUN_ID (its runs: {', '.join(ids[:5])}{', ...' if len(ids) > 5 else ''})"
        )
    rows = [r for r in campaign.rows if str(r.get("run_id")) == run_id]
    if not rows:
        raise ConfigError(f"bad value for --run: {run_id!r} is not a run of {str(folder)!r} ({len(ids)} runs)")
    row = rows[0]
    values = dict(campaign.fixed)
    values.update({p: row[p] for p in campaign.params if row.get(p) is not None and row[p] == row[p]})
    if not Path(campaign.scenario).is_file():  # a spec's relative path: relative to where the sweep ran
        raise ConfigError(
            f"the runs of {str(folder)!r} name their scenario {campaign.scenario!r}, which is not a file "
            "from here: run ego concrete in the folder the sweep or search ran in"
        )
    return campaign.scenario, str(row["controller"]), int(row["seed"]), values


def command(args) -> int:
    from ego.openscenario import is_scenario_file
    from ego.openscenario.concrete import split_values, write
    from ego.params import parse_overrides
    from ego.runner import run_command

    source = Path(args.source)
    if source.is_dir():
        if args.overrides:
            raise ConfigError("--set goes with an .xosc SOURCE; a folder's row has its values")
        template, controller, seed, values = _from_folder(source, args.run)
    elif is_scenario_file(str(source)):
        if args.run is not None:
            raise ConfigError("--run goes with a sweep or falsify folder, not an .xosc file")
        template, controller, seed, values = str(source), "CONTROLLER", 0, dict(parse_overrides(args.overrides))
    else:
        raise ConfigError(f"bad SOURCE {args.source!r} (expected an .xosc file or an ego sweep / falsify folder)")
    if not is_scenario_file(template):
        raise ConfigError(f"bad SOURCE {args.source!r}: its scenario {template!r} is not an .xosc file")
    own, rest = split_values(template, values)
    path = write(template, own, args.out, args.force)
    shown = ", ".join(f"{k}={v}" for k, v in own.items()) or "the defaults"
    print(f"wrote {path}: {Path(template).name} with {shown}")
    print(f"the same run: {run_command(str(path), controller, seed, rest)}")
    return 0
