"""Report 000's Mamdani fuzzy controller (section "(a) Fuzzy").

Inputs: the error e and its rate ec, each on [-10, 10]; output on [-100, 100]; seven
triangular sets NB NM NS ZO PS PM PB on every variable; the 7x7 rule table below (rows
E, columns EC). The same rule base drives both channels; the crisp output is multiplied
by 100 for Fx (N) and by 0.001 for delta (rad) because the two inputs differ by five
orders of magnitude. Optional input gains scale e and ec before they enter the rule base
(the report raised them to 3 and 20 for fast sine tracking).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

from ego.control.base import Observation, feedforward_param
from ego.control.fuzzy_engine import FastMamdani, table_rules, table_system
from ego.params import Params, param

TERMS = ("NB", "NM", "NS", "ZO", "PS", "PM", "PB")

#: Report 000's rule table: RULES[row E][column EC].
RULES = tuple(
    tuple(row.split())
    for row in (
        "NB NB NB NM NM NS ZO",
        "NB NB NM NM NS ZO PS",
        "NB NB NS NS ZO PS PM",
        "NB NM NS ZO PS PM PB",
        "NM NS ZO PS PS PB PB",
        "NS ZO PS PM PM PB PB",
        "ZO PS PM PM PB PB PB",
    )
)

INPUT_RANGE = 10.0
OUTPUT_RANGE = 100.0
#: Universe samples: every triangle vertex must be a sample (6 intervals between peaks).
INPUT_SAMPLES = 121
OUTPUT_SAMPLES = 601


#: the rule table as :func:`~ego.control.fuzzy_engine.table_rules` takes it
TABLE: dict[str, Any] = {
    "inputs": [("e", -INPUT_RANGE, INPUT_RANGE), ("ec", -INPUT_RANGE, INPUT_RANGE)],
    "outputs": [("u", -OUTPUT_RANGE, OUTPUT_RANGE)],
    "term_labels": TERMS,
    "tables": {"u": RULES},
    "samples": INPUT_SAMPLES,
    "output_samples": OUTPUT_SAMPLES,
}


def rule_base() -> Any:
    """Report 000's rule base as a scikit-fuzzy ControlSystem (inputs e, ec; output u)."""
    return table_system(**TABLE)


@lru_cache(maxsize=1)
def evaluator() -> FastMamdani:
    """The compiled rule base (its scikit-fuzzy rules, not the ControlSystem scikit-fuzzy
    would build of them: the same tables), shared by every controller instance in the process."""
    return FastMamdani.from_rules(table_rules(**TABLE), ["e", "ec"], ["u"])


@dataclass(frozen=True)
class FuzzyParams(Params):
    """Report 000's gains; input gains of 1 reproduce the lane-change experiments."""

    fx_gain: float = param(100.0, "N", "output gain: Fx = fx_gain * u", min=0, max=20000.0)
    delta_gain: float = param(0.001, "rad", "output gain: delta = delta_gain * u", min=0, max=1.0)
    ke_lon: float = param(1.0, "1/m", "longitudinal error input gain", min=0, max=1000.0)
    kec_lon: float = param(1.0, "s/m", "longitudinal error-rate input gain", min=0, max=1000.0)
    ke_lat: float = param(1.0, "1/m", "lateral error input gain", min=0, max=1000.0)
    kec_lat: float = param(1.0, "s/m", "lateral error-rate input gain", min=0, max=1000.0)
    feedforward: bool = feedforward_param()


class FuzzyController:
    """The report's fuzzy rule base on both channels, evaluated by :class:`FastMamdani`."""

    def __init__(self, params: FuzzyParams, dt: float) -> None:
        self.params = params
        self._eval = evaluator().single2
        p = params
        self._gains = (p.ke_lon, p.kec_lon, p.ke_lat, p.kec_lat, p.fx_gain, p.delta_gain)
        self._ff = p.feedforward
        self._u_lon = 0.0
        self._u_lat = 0.0

    def reset(self, *, seed: int | None = None) -> None:
        self._u_lon = self._u_lat = 0.0

    def step(self, obs: Observation) -> tuple[float, float]:
        ke_lon, kec_lon, ke_lat, kec_lat, fx_gain, delta_gain = self._gains
        u_lon = self._eval(ke_lon * (obs.s_ref - obs.s), kec_lon * (obs.ds_ref - obs.ds))
        u_lat = self._eval(ke_lat * (obs.d_ref - obs.d), kec_lat * (obs.dd_ref - obs.dd))
        self._u_lon = u_lon
        self._u_lat = u_lat
        delta = delta_gain * u_lat
        return fx_gain * u_lon, (delta + obs.steer_ff if self._ff else delta)

    #: the rule base's outputs before the output gains: pure numbers
    signal_units = {"fuzzy_u_lon": "-", "fuzzy_u_lat": "-"}

    def signals(self) -> dict[str, float]:
        return {"fuzzy_u_lon": self._u_lon, "fuzzy_u_lat": self._u_lat}
