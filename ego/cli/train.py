"""``ego train narma-l2``: train report 002's NARMA-L2 networks (:mod:`ego.train.narma_l2`)."""

from __future__ import annotations

from typing import Any

from ego.checks import check_count, check_seed
from ego.cli.common import EXIT_OK, declared, model_out, parse_range


def command(args: Any) -> int:
    from ego.control.narma import DEFAULT_MODEL
    from ego.train.narma_l2 import DataSpec, TrainSpec, train

    for value, what, cls, name in (
        (args.samples, "--samples", DataSpec, "samples"),
        (args.epochs, "--epochs", TrainSpec, "epochs"),
    ):
        info = declared(cls, name)
        check_count(value, what, int(info.min), int(info.max))
    v_lo, v_hi = parse_range(args.speeds, "--speeds", declared(DataSpec, "speed_min"))
    a_lo, a_hi = parse_range(args.accels, "--accels", declared(DataSpec, "accel_min"))
    r_lo, r_hi = parse_range(args.radii, "--radii", declared(DataSpec, "radius_min"))
    check_seed(args.seed, "--seed")
    out = model_out(args, DEFAULT_MODEL, "runs/narma_l2.npz", ".npz")
    if not args.install:  # the metadata written beside the weights
        from ego.paths import check_file_target

        check_file_target(out.with_suffix(".json"), "--out path", str(out))
    data = DataSpec(
        samples=args.samples,
        speed_min=v_lo,
        speed_max=v_hi,
        accel_min=a_lo,
        accel_max=a_hi,
        radius_min=r_lo,
        radius_max=r_hi,
    )
    train(TrainSpec(seed=args.seed, epochs=args.epochs, data=data), out)
    return EXIT_OK
