"""``ego report``: a results folder as one self-contained HTML file (:mod:`ego.report`)."""

from __future__ import annotations

import argparse


def add_parser(sub) -> argparse.ArgumentParser:
    """Add the ``report`` subcommand to ``ego``'s subparsers."""
    rep = sub.add_parser(
        "report",
        help="one self-contained HTML report of a compare, sweep or falsify folder",
        description="Turn the --out folder of ego compare, ego sweep or ego falsify into one HTML "
        "file that needs nothing else to open (no script, no external URL): a verdict table per "
        "scenario x controller x requirement (runs passed and failed, the worst robustness with "
        "its unit, collisions), every run's metrics, the folder's plots and every run's "
        "robustness inline, the ego run command that reproduces each failing run, and relative "
        "links to the recordings (.rrd) in the folder. See docs/report.md.",
        epilog="Examples:\n"
        "  ego compare emergency-brake --controllers pid,fuzzy --seeds 2 --out runs/cmp\n"
        "  ego report runs/cmp                      # writes runs/cmp/report.html\n"
        "  ego report runs/falsify-eb --out falsify-eb.html\n"
        "Exit status: 0 written; 2 bad input (DIR not such a folder, --out not an .html file "
        "or a file ego report did not write), nothing written.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    rep.add_argument("dir", metavar="DIR", help="the --out folder of ego compare, ego sweep or ego falsify")
    rep.add_argument("--out", default=None, metavar="FILE.html", help="where to write (default DIR/report.html)")
    rep.add_argument("--force", action="store_true", help="replace --out even if it is a file ego report did not write")
    return rep


def command(args) -> int:
    from ego.report import write

    campaign, path = write(args.dir, args.out, args.force)
    failing = sum(1 for r in campaign.rows if campaign.failures(r))
    print(f"wrote {path}: {len(campaign.rows)} runs of {campaign.kind} {campaign.scenario}, {failing} failing")
    return 0
