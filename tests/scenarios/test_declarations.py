"""What a scenario declares about its results matches what its runs produce: every metric
is declared (with a unit), every declared metric shows up, every plotted column is in the
trace, and every trace column has a unit."""

import numpy as np
import pytest

from ego.results import metrics as m
from ego.runner import RunSpec, resolve, run
from ego.scenarios.tracking import SineTracking

#: scenario -> the runs that between them produce every metric it declares
RUNS = {
    "curve": [("pid", {}), ("pid", {"lead": "20"})],
    "lane-centering": [
        ("cascade-pid", {"duration": "20"}),
        ("cascade-pid", {"duration": "20", "plant": "dynamic-bicycle"}),
    ],
    "platoon": [
        ("pid", {"duration": "30"}),
        (
            "pid",
            {"duration": "30", "followers": "2", "start_error": "5", "sine_amplitude": "3", "sine_transient": "10"},
        ),
    ],
    "report-000": [("fuzzy", {"duration": "12"}), ("rbf-smc", {"duration": "12", "case": "sine", "omega": "0.5"})],
}


def covered(key: str, names: set[str], prefixes: tuple[str, ...]) -> bool:
    """Declared by name, or under a declared ``prefix.`` (a nested metric that is None when
    it does not apply, e.g. ``frequency_gain`` without a sine, is its prefix without the dot)."""
    return key in names or key.startswith(prefixes) or f"{key}." in prefixes


def declared(cls, config, spec=None):
    """The metrics declared for a run: the scenario's, and with ``spec`` its requirements'
    robustness (ego.runner.declared_metrics declares those)."""
    from ego.runner import declared_metrics

    specs = declared_metrics(spec) if spec is not None else cls.metrics_declared(config)
    names = {s.name for s in specs if not s.name.endswith(".")}
    prefixes = tuple(s.name for s in specs if s.name.endswith("."))
    return specs, names, prefixes


@pytest.fixture(scope="module", params=list(RUNS))
def runs(request):
    scenario = request.param
    return scenario, [(RunSpec(scenario, c, 0, o), run(RunSpec(scenario, c, 0, o))) for c, o in RUNS[scenario]]


@pytest.mark.sumo
def test_every_metric_of_a_run_is_declared_and_every_declared_one_shows_up(runs):
    scenario, results = runs
    seen: set[str] = set()
    for spec, result in results:
        r = resolve(spec)
        cls, config = r.scenario_cls, r.config
        specs, names, prefixes = declared(cls, config, spec)
        assert len({s.name for s in specs}) == len(specs), "a metric declared twice"
        assert all(s.unit for s in specs)
        keys = m.flatten(result.metrics)
        missing = [k for k in keys if not covered(k, names, prefixes)]
        assert not missing, f"{scenario}: undeclared metrics {missing}"
        seen |= set(keys)
    never = [
        s.name for s in specs if not (s.name in seen or any(k.startswith(s.name) or f"{k}." == s.name for k in seen))
    ]
    assert not never, f"{scenario}: declared but never reported: {never}"


@pytest.mark.sumo
def test_every_plot_is_a_trace_column_and_every_column_has_a_unit(runs):
    scenario, results = runs
    for spec, result in results:
        r = resolve(spec)
        cls, config = r.scenario_cls, r.config
        plots = cls.plots + tuple(p for p in cls.compare_plots(config) if p not in cls.plots)
        assert plots, f"{scenario} declares nothing to plot"
        for plot in plots:
            optional = getattr(plot, "gain_columns", ())  # controller signals, when there
            for column in plot.columns:
                if column not in optional:
                    assert column in result.columns and result.units[column], (plot, column)
            assert "[" not in getattr(plot, "label", "")  # the unit comes from the column
        declared_columns = [c for c in result.units if result.units[c]]
        assert result.columns[: len(declared_columns)] == tuple(declared_columns)
        assert result.trace.shape[1] == len(result.columns)


def test_sine_tracking_declares_every_metric_it_computes():
    """Its base (the motorway) runs elsewhere; its metrics come from its trace alone."""
    n = 50
    t = np.arange(n) * 0.1
    cols = {
        "t": t,
        "e_lat": np.sin(t),
        "ds": np.full(n, 20.0),
        "speed_ref": np.full(n, 25.0),
        "ttc_front": np.full(n, np.inf),
        "ttc_rear": np.linspace(9.0, 3.0, n),
        "lat_accel": np.cos(t),
        "speed": np.full(n, 20.0),
    }
    columns = tuple(cols)
    trace = np.column_stack([cols[c] for c in columns])
    metrics = SineTracking._metrics(None, trace, columns)
    specs, names, prefixes = declared(SineTracking, SineTracking.config_cls())
    assert set(metrics) <= names
    assert {s.name for s in SineTracking.metric_specs} == set(metrics)
