"""Parameter references and ``${...}`` expressions (OpenSCENARIO 1.1), and parameters that
refer to each other."""

from __future__ import annotations

import pytest

from ego.openscenario.expressions import ExpressionError, evaluate, resolve

VALUES = {"a": 10.0, "b": 4, "speed": 13.889, "name": "car", "flag": True}


@pytest.mark.parametrize(
    "expr,value",
    [
        ("1 + 2 * 3", 7.0),
        ("(1 + 2) * 3", 9.0),
        ("$a - $b - 1", 5.0),  # left to right
        ("$a / $b / 2", 1.25),
        ("-$a + 3", -7.0),
        ("-(-$b)", 4.0),
        ("2 * -3", -6.0),
        ("$speed * 3.6", 13.889 * 3.6),
        ("1.5e2 / 3", 50.0),
        (".5 + .25", 0.75),
        ("((($a)))", 10.0),
        ("$a+$b*2-(3-1)/2", 17.0),
    ],
    ids=lambda x: str(x),
)
def test_evaluates(expr, value):
    assert evaluate(expr, VALUES) == pytest.approx(value, abs=1e-12)


@pytest.mark.parametrize(
    "expr,message",
    [
        ("", "empty expression '${}'"),
        ("1 +", "unexpected the end in expression '${1 +}' (expected a number, a $parameter or '(')"),
        ("(1 + 2", "missing ')' in expression '${(1 + 2}'"),
        ("1 + 2)", "unexpected ')' in expression '${1 + 2)}'"),
        ("2 ** 3", "unexpected '*' in expression '${2 ** 3}' (expected a number, a $parameter or '(')"),
        (
            "cbrt(4)",
            "unknown function 'cbrt' in expression '${cbrt(4)}' (functions: round, floor, ceil, sqrt, abs, sign, "
            "sin, cos, tan, asin, acos, atan, pow, min, max)",
        ),
        (
            "$nope + 1",
            "parameter '$nope' in expression '${$nope + 1}' is not declared (declared: a, b, speed, name, flag)",
        ),
        ("$name * 2", "parameter '$name' = 'car' in expression '${$name * 2}' is not a number"),
        ("$flag + 1", "parameter '$flag' in expression '${$flag + 1}' is a boolean, not a number"),
        ("$a / (2 - 2)", "division by zero in expression '${$a / (2 - 2)}'"),
    ],
)
def test_refuses(expr, message):
    with pytest.raises(ExpressionError) as err:
        evaluate(expr, VALUES)
    assert str(err.value) == message


def test_resolve():
    assert resolve("12.5", VALUES) == "12.5"  # a literal is the attribute itself
    assert resolve("$name", VALUES) == "car"  # a whole-value reference
    assert resolve("${$a * 2}", VALUES) == 20.0
    with pytest.raises(ExpressionError, match=r"parameter '\$x' is not declared"):
        resolve("$x", VALUES)
    with pytest.raises(ExpressionError, match="unterminated"):
        resolve("${1 + 2", VALUES)


def test_declarations_follow_overrides(tmp_path):
    """A declaration referring to an earlier parameter sees that parameter's set value;
    ``ego run --set`` of a declared parameter reaches the storyboard."""
    import shutil
    from pathlib import Path

    from ego.openscenario.loader import load

    shipped = Path(__file__).resolve().parents[2] / "scenarios" / "openscenario"
    for name in ("ccrb.xosc", "straight3.xodr"):
        shutil.copy(shipped / name, tmp_path / name)
    model = load(tmp_path / "ccrb.xosc")
    assert model.values["LeadSpeed"] == pytest.approx(13.889)
    model = load(tmp_path / "ccrb.xosc", {"EgoSpeed": "20"})
    assert model.values["LeadSpeed"] == 20.0 and model.values["EgoSpeed"] == 20.0
    model = load(tmp_path / "ccrb.xosc", {"EgoSpeed": 20.0, "LeadSpeed": 5.0})
    assert model.values["LeadSpeed"] == 5.0
    lead = model.init["lead"][0].position
    assert lead.s == pytest.approx(300.0 + 12.0 + 2.25)  # ${$EgoFront + $LeadGap + 2.25}
