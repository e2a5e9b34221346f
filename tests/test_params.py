"""Parameter parsing and validation (the CLI's --set)."""

from dataclasses import dataclass

import pytest

from ego.params import ConfigError, apply_overrides, describe, param, parse_overrides


@dataclass(frozen=True)
class Demo:
    speed: float = param(20.0, "m/s", "a speed", min=0.0, max=40.0)
    count: int = param(3, "-", "a count", min=1)
    flag: bool = param(False, "-", "a flag")
    lane: int = param(1, "-", "a lane", choices=(0, 1, 2))
    gain: float = param(1.0, "N", "a gain", min=0.0, min_exclusive=True)


def test_describe_lists_fields_with_units():
    info = {i.name: i for i in describe(Demo)}
    assert info["speed"].unit == "m/s" and info["speed"].default == 20.0
    assert list(info) == ["speed", "count", "flag", "lane", "gain"]


@pytest.mark.parametrize(
    "text, expected",
    [
        ("speed=12.5", 12.5),
        ("speed=0", 0.0),
        ("count=7", 7),
        ("flag=true", True),
        ("flag=0", False),
        ("lane=2", 2),
        ("gain=0.5", 0.5),
    ],
    ids=lambda v: str(v),
)
def test_good_values_are_typed(text, expected):
    key = text.split("=")[0]
    cfg, rest = apply_overrides(Demo(), parse_overrides([text]))
    assert getattr(cfg, key) == expected and type(getattr(cfg, key)) is type(expected) and not rest


@pytest.mark.parametrize(
    "text, message",
    [
        ("speed=fast", "bad value for speed: 'fast' (expected a number from 0 to 40 (m/s))"),
        ("speed=41", "bad value for speed: 41 (expected a number from 0 to 40 (m/s))"),
        ("speed=nan", "bad value for speed: nan"),
        ("count=2.5", "bad value for count: '2.5' (expected a whole number of at least 1)"),
        ("count=0", "bad value for count: 0"),
        ("flag=maybe", "bad value for flag: 'maybe' (expected true or false)"),
        ("lane=3", "bad value for lane: 3 (expected one of 0, 1, 2)"),
        ("gain=0", "bad value for gain: 0 (expected a number above 0 (N))"),
        ("nope=1", "unknown parameter 'nope' (known: count, flag, gain, lane, speed)"),
    ],
    ids=lambda v: str(v),
)
def test_bad_values_are_named_with_what_is_allowed(text, message):
    with pytest.raises(ConfigError) as err:
        apply_overrides(Demo(), parse_overrides([text]))
    assert str(err.value).startswith(message)
    assert "\n" not in str(err.value)


def test_malformed_set_item():
    with pytest.raises(ConfigError, match="expected key=value"):
        parse_overrides(["speed"])


def test_unknown_keys_are_returned_when_not_strict():
    cfg, rest = apply_overrides(Demo(), {"speed": "5", "other": "1"}, strict=False)
    assert cfg.speed == 5.0 and rest == {"other": "1"}
