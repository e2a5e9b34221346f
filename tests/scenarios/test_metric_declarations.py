"""Flattened metric names against a scenario's declarations: units, headlines, labels."""

import pytest

from ego.results.metrics import declaration, headline_names, metric_units, with_unit
from ego.results.trace import Metric

DECLARED = (
    Metric("status", "-"),
    Metric("min_gap", "m", headline=True),
    Metric("followers.", "m"),
    Metric("followers.f1.min_ttc", "s"),
    Metric("settle_times.", "s", headline=True),
    Metric("string_stable", "-", headline=True),
    Metric("settle", "s"),
)


@pytest.mark.parametrize(
    "name, unit",
    [
        ("min_gap", "m"),
        ("followers.f2.min_gap", "m"),  # the prefix
        ("followers.f1.min_ttc", "s"),  # an exact name beats a prefix
        ("settle_times.brake@10s", "s"),
        ("settle", "s"),  # "settle_times." does not declare "settle"
        ("settle_timesX", ""),  # nor anything that only starts alike
        ("unknown", ""),
    ],
    ids=["exact", "prefix", "exact-over-prefix", "dotted", "not-a-prefix", "no-dot", "undeclared"],
)
def test_a_flattened_name_takes_the_unit_of_its_declaration(name, unit):
    assert metric_units(DECLARED, [name]) == {name: unit}


def test_the_longest_prefix_declares_a_name():
    declared = (Metric("a.", "m"), Metric("a.b.", "s"))
    assert declaration(declared, "a.b.c").unit == "s" and declaration(declared, "a.x").unit == "m"


def test_headlines_follow_the_declaration_order_with_prefixes_expanded_in_the_order_met():
    present = [
        "status",
        "string_stable",
        "settle_times.stop",
        "followers.f1.min_ttc",
        "min_gap",
        "settle_times.brake@10s",
        "settle_times.stop",
    ]
    assert headline_names(DECLARED, present) == [
        "min_gap",
        "settle_times.stop",
        "settle_times.brake@10s",
        "string_stable",
    ]
    assert headline_names(DECLARED, ["status"]) == []


@pytest.mark.parametrize("unit, label", [("m/s", "speed [m/s]"), ("-", "speed"), ("", "speed")])
def test_a_label_shows_a_real_unit_only(unit, label):
    assert with_unit("speed", unit) == label
