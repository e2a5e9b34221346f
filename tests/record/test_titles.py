"""Panel titles and unit paths of a recording (pure: no run)."""

import pytest

from ego.record.base import Series, unit_path
from ego.record.rerun_recorder import TITLE_SERIES, panel_title


@pytest.mark.parametrize(
    "panel, members, title",
    [
        (
            "plots/a_x",
            [Series("a", "plots/a_x/applied", "m/s^2", "applied"), Series("b", "plots/a_x/plan", "m/s^2", "plan")],
            "a_x [m/s^2]: applied blue, plan orange",
        ),
        (
            "plots/lateral_error",
            [Series("e", "plots/lateral_error/ego", "m", "lateral error (actual - reference)")],
            "lateral error [m]",
        ),
        (
            "plots/controller/1",
            [Series("u", "plots/controller/1/fuzzy_u_lon", "-", "fuzzy_u_lon")],
            "controller [-]: fuzzy_u_lon",
        ),
        (
            "plots/many",
            [Series(f"c{i}", f"plots/many/s{i}", "m", f"s{i}") for i in range(TITLE_SERIES + 1)],
            "many [m]",
        ),
    ],
    ids=["symbols-kept", "one-series", "controller-one-signal", "legend-instead"],
)
def test_panel_titles(panel, members, title):
    assert panel_title(panel, members) == title


@pytest.mark.parametrize(
    "unit, part",
    [("N/(m s)", "N_per_m_s"), ("m/s^2", "m_per_s_2"), ("rad s/m", "rad_s_per_m"), ("-", "1"), ("", "1")],
    ids=["per-product", "power", "product", "dash", "none"],
)
def test_a_unit_as_an_entity_path_part(unit, part):
    assert unit_path(unit) == part
