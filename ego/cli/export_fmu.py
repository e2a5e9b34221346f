"""``ego export-fmu``: one of ego's vehicle models as an FMI 2.0 co-simulation FMU."""

from __future__ import annotations

from typing import Any

from ego.cli.common import EXIT_OK
from ego.params import parse_overrides


def command(args: Any) -> int:
    from ego.fmi.export import export_fmu

    print(f"wrote {export_fmu(args.model, args.out, parse_overrides(args.overrides))}")
    return EXIT_OK
