"""What every command of the ``ego`` command line shares: exit codes, the one-line usage
errors, small argument checks."""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ego.checks import check_output_file
from ego.params import ConfigError, describe, did_you_mean

EXIT_OK, EXIT_NOT_COMPLETED, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


def choice(value: str, allowed, what: str) -> str:
    """``value`` if it is one of ``allowed``, else ConfigError (with the closest name)."""
    if value not in allowed:
        raise ConfigError(f"bad {what} {value!r} (allowed: {', '.join(allowed)}){did_you_mean(value, allowed)}")
    return value


def terminate(signum, frame) -> None:
    """SIGTERM ends a run like Ctrl-C: status interrupted, metrics so far, recording closed."""
    from ego.usercode import SignalInterrupt

    raise SignalInterrupt


class Parser(argparse.ArgumentParser):
    """argparse that reports bad usage in one line and exits with 2."""

    def error(self, message: str) -> None:  # pragma: no cover - exercised through main()
        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:  # a misspelt command or choice: name the closest
            message += did_you_mean(choice.group(1), re.findall(r"'([^']*)'", choice.group(2)))
        value = re.fullmatch(r"argument (--[\w-]+)\S*: expected one argument", message)
        if value:  # argparse takes "--accels -1,0" for an option -1,0: the value goes after "="
            message += f" (a value that starts with - is written {value.group(1)}=VALUE)"
        raise ConfigError(message)

    def _print_message(self, message: str, file=None) -> None:
        """As argparse's, but a failed write (help on a full stdout) is not swallowed."""
        if message:
            (file or sys.stderr).write(message)


# -- option groups every front end shares (ego run, compare, sweep, falsify, tune) -----------
REQUIRE_HELP = (
    "a requirement in signal temporal logic over the trace's signals, on top of the "
    "scenario's defaults (repeatable; docs/requirements.md), e.g. "
    '"keep_gap: always (gap_front >= 2 m)"'
)


def add_out(p: argparse.ArgumentParser, help: str, metavar: str = "DIR", required: bool = True) -> None:
    """``--out``: the folder (or file) the command writes."""
    if required:
        p.add_argument("--out", required=True, metavar=metavar, help=help)
    else:
        p.add_argument("--out", default=None, metavar=metavar, help=help)


def add_jobs(p: argparse.ArgumentParser, help: str, metavar: str = "N") -> None:
    """``--jobs``: how many runs at once (a whole number; checked against MAX_JOBS later)."""
    from ego.checks import whole_number

    p.add_argument("--jobs", type=whole_number("--jobs"), default=None, metavar=metavar, help=help)


def add_engine(p: argparse.ArgumentParser, help: str) -> None:
    """``--engine``: process or ray (checked against ego.parallel.ENGINES later)."""
    p.add_argument("--engine", default="process", metavar="ENGINE", help=help)


def add_address(p: argparse.ArgumentParser, help: str) -> None:
    """``--address``: with ``--engine ray``, the cluster to join."""
    p.add_argument("--address", default=None, metavar="ADDR", help=help)


def add_require(p: argparse.ArgumentParser, help: str = REQUIRE_HELP) -> None:
    """``--require "NAME: FORMULA"``, repeatable."""
    p.add_argument("--require", action="append", default=[], metavar='"NAME: FORMULA"', help=help)


def add_preventable(p: argparse.ArgumentParser) -> None:
    """``--preventable`` of ``ego compare`` and ``ego sweep``."""
    p.add_argument(
        "--preventable",
        action="store_true",
        help="after every collision also run UN R157's careful driver on the same scenario and "
        "report collision_preventable (a second run per collision; docs/requirements.md)",
    )


def add_requirement_period(p: argparse.ArgumentParser) -> None:
    """``--requirement-period S``: requirements on a grid of samples S s apart (0: every
    sample of the trace, the default)."""
    p.add_argument(
        "--requirement-period",
        default=0.0,
        metavar="S",
        help="evaluate the requirements on samples S s apart (e.g. 0.1, the SUMO step) instead of "
        "every sample of the trace (0, the default; docs/requirements.md)",
    )


PATH_HELP = (
    "with an .xosc file: a folder to look in for its road and catalog files when they are not "
    "where the file says (repeatable; searched after the scenario's own folder, before $EGO_PATH; "
    "docs/openscenario.md)"
)


def add_path(p: argparse.ArgumentParser) -> None:
    """``--path DIR``, repeatable: the search folders of a scenario's files (ego.openscenario.files)."""
    p.add_argument("--path", dest="search_path", action="append", default=[], metavar="DIR", help=PATH_HELP)


@contextmanager
def search_path(folders: list[str]) -> Iterator[None]:
    """``$EGO_PATH`` with ``folders`` (each checked: an existing folder) in front, for the
    command's duration (worker processes inherit it)."""
    from ego.openscenario.files import SEARCH_ENV, forget_warnings

    forget_warnings()  # each command prints its warnings once (a Python caller's commands too)
    if not folders:
        yield
        return
    for f in folders:
        if not Path(f).is_dir():
            raise ConfigError(f"bad --path {f!r}: not a folder")
    before = os.environ.get(SEARCH_ENV)
    os.environ[SEARCH_ENV] = os.pathsep.join([str(Path(f).resolve()) for f in folders] + ([before] if before else []))
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(SEARCH_ENV, None)
        else:
            os.environ[SEARCH_ENV] = before


def add_set(p: argparse.ArgumentParser, help: str) -> None:
    """``--set KEY=VALUE``, repeatable, into ``args.overrides``."""
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", help=help)


def check_ego_name(name: str | None) -> None:
    """``--ego ""`` (or blanks) is no entity: refused rather than read as the default Ego."""
    if name is not None and not name.strip():
        raise ConfigError(f"bad value for --ego: {name!r} (an entity of the .xosc file, e.g. --ego Ego)")


def ego_entity(args, overrides: dict) -> dict:
    """``--ego ENTITY`` (``ego run`` / ``ego compare``) as the file scenario's ``ego_entity``
    parameter; ConfigError with a built-in scenario."""
    if args.ego is None:
        return overrides
    check_ego_name(args.ego)
    from ego.openscenario import is_scenario_file

    if not is_scenario_file(args.scenario):
        raise ConfigError(f"--ego goes with an OpenSCENARIO file (.xosc), not {args.scenario!r}")
    return {**overrides, "ego_entity": args.ego}


def parse_range(text: str, what: str, declared) -> tuple[float, float]:
    """``LO,HI`` within the bounds ``declared`` (a parameter's ``ParamInfo``) gives."""
    try:
        lo, hi = (float(x) for x in text.split(","))
    except ValueError:
        raise ConfigError(f"bad value for {what}: {text!r} (expected LO,HI, e.g. 20,40)") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
        raise ConfigError(f"bad value for {what}: {text!r} (expected finite LO <= HI)")
    if lo < declared.min or hi > declared.max:
        raise ConfigError(
            f"bad value for {what}: {text!r} (expected {declared.unit} within {declared.min:g}..{declared.max:g})"
        )
    return lo, hi


def declared(cls, name: str):
    """The declaration (``ParamInfo``) of parameter ``name`` of ``cls``."""
    return next(i for i in describe(cls) if i.name == name)


def model_out(args, shipped, default: str, suffix: str):
    """Where ``ego train``/``ego tune`` write: --out, the shipped file with --install (and
    only then), else ``default`` in the working directory."""

    if args.install and args.out is not None:
        raise ConfigError("give --out or --install, not both")
    if args.install:
        return Path(shipped)
    return check_output_file(default if args.out is None else args.out, "--out path", suffix)  # "" is refused
