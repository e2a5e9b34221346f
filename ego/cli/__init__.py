"""The ``ego`` command line.

    ego run SCENARIO --controller NAME [--record PATH] [--trace PATH] [--seed N] [--set key=value ...]
            [--json] [--backend sumo|highway-env] [--video PATH.gif|PATH.mp4]
            [--require "NAME: FORMULA" ...]
    ego compare SCENARIO --controllers A,B@key=value,... [--seeds N] [--set key=value ...] --out DIR
                [--traces csv|parquet|mat] [--backend sumo|highway-env] [--require "NAME: FORMULA" ...]
    ego sweep SPEC.toml --out DIR [--engine process|ray] [--jobs N] [--address ADDR]
              [--record none|failed|all] [--plot X,Y[:METRIC] ...] [--require "NAME: FORMULA" ...]
    ego falsify SPEC.toml --out DIR [--engine process|ray] [--jobs N] [--budget N]
                [--optimizer cma|bo|bo-tpe|random|lhs] [--until first|budget]
    ego report DIR [--out FILE.html] [--force]
    ego concrete FILE.xosc|DIR --out FILE.xosc [--set key=value ...] [--run RUN_ID] [--force]
    ego list [--json]
    ego train narma-l2 [--seed N] [--samples N] [--epochs N] [--out PATH]
    ego tune lane-centering [--quick] [--workers N] [--seed N] [--drives V[:OFF],...] [--out PATH]
                            [--cost model|sumo] [--engine process|ray] [--address ADDR] [--duration S]

Units come from the scenario's declarations: ``ego run`` prints each numeric metric
followed by its unit, and ``--json`` adds a top-level ``"units"`` object (flattened metric
name, e.g. ``settle_times.brake@10s``, -> unit; ``-`` for a pure number, a code or text,
``""`` where the scenario declares none) beside the metrics and ``"events"``. ``ego list
--json`` gives per scenario its ``parameters``, ``metrics`` (name, unit, description,
headline; a name ending in ``.`` stands for every metric under it) and trace ``columns``
(name, unit, description), and per controller its ``parameters``.

Exit status of ``ego run``: 0 the run completed, or ``ended`` (the ``duration`` ran out
before the scenario's end, in a scenario whose end the controller does not decide: a
shortened run, not a failure); 1 it ended in a collision, diverged or timed out (the
duration ran out during a manoeuvre; the metrics are still printed); 130 interrupted by
Ctrl-C or SIGTERM (status ``interrupted``, the metrics so far printed, the recording
closed); 2 bad input (unknown name, bad value), with one line on stderr naming it and what
is allowed. ``ego compare`` and ``ego sweep``: 0 every run gave a result (a collision is a
result); 1 some run ended in ``error`` (ego could not run it); 130 interrupted (what
finished is written); 2 bad input, or ``--out`` held by another ego process.
docs/reliability.md has the details.

The package holds one module per command (``ego.cli.run``, ``compare``, ``sweep``, ``falsify``, ``report``, ``concrete``, ``list``
as ``catalogue``, ``train``, ``tune``), each with ``command(args) -> exit status``;
:data:`COMMANDS` maps a command's name to its module and :func:`main` dispatches through it.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence

from ego.cli.common import EXIT_INTERRUPTED, EXIT_NOT_COMPLETED, EXIT_OK, EXIT_USAGE, search_path, terminate
from ego.params import ConfigError

#: command name -> the module that runs it (imported when the command runs)
COMMANDS = {
    "run": "ego.cli.run",
    "compare": "ego.cli.compare",
    "sweep": "ego.cli.sweep",
    "falsify": "ego.cli.falsify",
    "list": "ego.cli.catalogue",
    "train": "ego.cli.train",
    "tune": "ego.cli.tune",
    "export-fmu": "ego.cli.export_fmu",
    "report": "ego.cli.report",
    "concrete": "ego.cli.concrete",
}


def main(argv: Sequence[str] | None = None) -> int:
    import signal

    from ego.cli.parser import parser
    from ego.outputs import OutputError
    from ego.sim import SimError  # every backend's (SUMO's SumoError is one)

    if argv is None:  # the command itself, not a call from Python code
        signal.signal(signal.SIGTERM, terminate)
    try:
        args = parser().parse_args(argv)
        module = COMMANDS.get(args.command)
        if module is None:
            parser().print_help()
            return EXIT_USAGE
        with search_path(getattr(args, "search_path", None) or []):
            return int(importlib.import_module(module).command(args))
    except (ConfigError, SimError) as exc:
        print(f"ego: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except OutputError as exc:  # a write failed after the checks (a full disk): one line
        print(f"ego: error: {exc}", file=sys.stderr)
        return EXIT_NOT_COMPLETED
    except KeyboardInterrupt:
        print("ego: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # e.g. piped into head: stop quietly
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK


__all__ = ["COMMANDS", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_USAGE", "main"]

if __name__ == "__main__":
    sys.exit(main())
