"""The layout of a recording, read back from real .rrd files: the embedded blueprint's views
and the data under each of them."""

import re
from dataclasses import replace

import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import RrdReader

from ego.record.rerun_recorder import PALETTE, THRESHOLD
from ego.runner import RunSpec, build

pytestmark = pytest.mark.sumo


def _record(tmp_path_factory, spec: RunSpec):
    """Run ``spec`` with a recording; (rrd path, result, the scenario's declared series)."""
    path = tmp_path_factory.mktemp("layout") / f"{spec.scenario}.rrd"
    sc = build(replace(spec, record=str(path)))
    result = sc.run()
    return path, result, sc.loop.series()


@pytest.fixture(scope="module")
def brake(tmp_path_factory):
    # fuzzy-pid: six gains in six units, the case that mixed units most
    return _record(tmp_path_factory, RunSpec("emergency-brake", "fuzzy-pid", 0))


@pytest.fixture(scope="module")
def curve(tmp_path_factory):
    return _record(tmp_path_factory, RunSpec("curve", "fuzzy-curve", 0))  # no lead


@pytest.fixture(scope="module")
def platoon(tmp_path_factory):
    return _record(tmp_path_factory, RunSpec("platoon", "bp-pid-acc", 0, {"duration": "40"}))


def views(path) -> list[dict]:
    """The blueprint's views: kind, name, origin and their properties (component -> value)."""
    reader = RrdReader(path)
    (store,) = reader.blueprints()
    found: dict[str, dict] = {}
    for chunk in reader.stream(store=store):
        m = re.match(r"/view/([0-9a-f-]+)(/.*)?$", chunk.entity_path)
        if not m:
            continue
        view = found.setdefault(m.group(1), {"overrides": {}})
        rb = chunk.to_record_batch()
        for name in rb.schema.names:
            value = rb.column(name).to_pylist()[-1]
            if m.group(2) and "/overrides/" in m.group(2):
                view["overrides"][name] = value
            elif ":" in name:
                view[name.split(":", 1)[1]] = value[0] if isinstance(value, list) and len(value) == 1 else value
    return list(found.values())


def plot_views(path) -> list[dict]:
    return [v for v in views(path) if v["class_identifier"] == "TimeSeries"]


def entities(path, component: str) -> dict[str, list]:
    """Entity path -> (time s, value) rows of one component, in time order."""
    out: dict[str, list] = {}
    for chunk in RrdReader(path).stream():
        rb = chunk.to_record_batch()
        if component not in rb.schema.names:
            continue
        t = (
            rb.column("sim_time").cast(pa.int64()).to_numpy() / 1e9
            if "sim_time" in rb.schema.names
            else np.full(rb.num_rows, np.nan)
        )
        out.setdefault(chunk.entity_path, []).extend(zip(t, rb.column(component).to_pylist()))
    return {e: sorted(rows, key=lambda r: r[0]) for e, rows in out.items()}


def test_the_wide_view_follows_the_ego_over_300_m_without_labels(brake):
    path, result, _ = brake
    spatial = [v for v in views(path) if v["class_identifier"] == "2D"]
    assert all(v["space_origin"] == "world/follow" for v in spatial)  # no whole-road strip
    wide = next(v for v in spatial if v["display_name"].startswith("300 m around the ego"))
    x0, x1 = wide["range"]["x_range"]
    assert (x0, x1) == (-100.0, 200.0)
    assert wide["overrides"]["LineStrips2D:show_labels"] == [False]
    # the frame the views are drawn in sits on the ego at every SUMO step (the map is mirrored)
    follow = entities(path, "Transform3D:translation")["/world/follow"]
    boxes = entities(path, "LineStrips2D:strips")["/world/map/vehicles"]
    labels = entities(path, "LineStrips2D:labels")["/world/map/vehicles"]
    assert len(follow) == len(boxes) == result.metrics["steps"] // 10 + 1
    for (_, (xyz,)), (_, strips), (_, ids) in zip(follow, boxes, labels):
        centre = np.mean(np.array(strips[ids.index("ego")])[:4], axis=0)
        assert abs(xyz[0] - centre[0]) < 2.0 and abs(xyz[1] + centre[1]) < 4.0


def test_no_panel_mixes_units_and_controller_signals_have_theirs(brake):
    path, result, series = brake
    declared = {"/" + s.path: s for s in series}
    recorded = entities(path, "Scalars:scalars")
    plots = plot_views(path)
    assert len(plots) == len({s.panel for s in series if not s.states})
    for view in plots:
        members = [s for e, s in declared.items() if e.startswith(f"/{view['space_origin']}/")]
        units = {s.unit for s in members}
        assert len(units) == 1, (view["display_name"], units)
        unit = units.pop()
        assert f" [{unit}]" in view["display_name"] if unit else "[" not in view["display_name"]
        assert all(e in recorded for e in declared if e.startswith(f"/{view['space_origin']}/"))
    gains = {v["display_name"] for v in plots if v["space_origin"].startswith("plots/controller/")}
    assert gains == {
        f"controller [{u}]: {name}"
        for name, u in (
            ("kp_lon", "N/m"),
            ("ki_lon", "N/(m s)"),
            ("kd_lon", "N s/m"),
            ("kp_lat", "rad/m"),
            ("ki_lat", "rad/(m s)"),
            ("kd_lat", "rad s/m"),
        )
    }
    assert result.units["kp_lon"] == "N/m"  # the run's units carry them too


def test_titles_name_each_series_by_its_colour_and_legends_stay_hidden(brake):
    path, _, _ = brake
    plots = {v["space_origin"]: v for v in plot_views(path)}
    speed = plots["plots/speed"]
    assert speed["display_name"] == "speed [m/s]: ego blue, reference orange"
    assert plots["plots/ttc"]["display_name"] == "ttc [s]: front blue, rear orange, trigger, AEB red"
    assert plots["plots/lateral_error"]["display_name"] == "lateral error [m]"
    assert all(v["visible"] is False for v in plots.values())  # PlotLegend
    colors = {e: rows[0][1] for e, rows in entities(path, "SeriesLines:colors").items()}
    names = {e: rows[0][1] for e, rows in entities(path, "SeriesLines:names").items()}
    packed = [(r << 24) | (g << 16) | (b << 8) | 0xFF for r, g, b in (PALETTE[0][1], PALETTE[1][1], THRESHOLD[1])]
    assert [colors[f"/plots/ttc/{e}"][0] for e in ("front", "rear", "trigger")] == packed
    assert names["/plots/ttc/trigger"] == ["trigger 3 s"] and names["/plots/ttc/aeb"] == ["AEB 1 s"]
    assert names["/plots/speed/ego"] == ["ego"]  # no unit glued on: the panel has it


def test_the_ttc_panel_has_its_thresholds_over_the_whole_run(brake):
    path, result, _ = brake
    scalars = entities(path, "Scalars:scalars")
    for entity, value in (("/plots/ttc/trigger", 3.0), ("/plots/ttc/aeb", 1.0)):
        rows = scalars[entity]
        assert len(rows) == result.metrics["steps"]
        assert {v[0] for _, v in rows} == {value}


def test_the_manoeuvre_phase_is_a_named_state(brake):
    path, result, _ = brake
    states = entities(path, "StateChange:state")["/states/manoeuvre"]
    assert [s[0] for _, s in states] == ["cruise", "lane change", "done"]
    trigger = next(e.t for e in result.events if e.kind == "trigger")
    assert states[1][0] == pytest.approx(trigger, abs=0.011)  # the row after the trigger step
    timeline = [v for v in views(path) if v["class_identifier"] == "StateTimeline"]
    assert [v["space_origin"] for v in timeline] == ["states"]
    assert "/states/manoeuvre" not in entities(path, "Scalars:scalars")


def test_the_recording_opens_at_its_end_with_the_events_readable(brake):
    path, _, _ = brake
    reader = RrdReader(path)
    (store,) = reader.blueprints()
    panel = {}
    for chunk in reader.stream(store=store):
        if chunk.entity_path == "/time_panel":
            rb = chunk.to_record_batch()
            panel.update({n: rb.column(n).to_pylist()[-1] for n in rb.schema.names})
    assert panel["TimePanelBlueprint:play_state"] == [3]  # following: the latest data
    log = next(v for v in views(path) if v["class_identifier"] == "TextLog")
    assert [c["kind"] for c in log["text_log_columns"]] == [2, 3]  # level and body: no entity path


def test_a_curve_without_a_lead_has_no_empty_panel(curve):
    path, result, _ = curve
    scalars = entities(path, "Scalars:scalars")
    plots = plot_views(path)
    assert "plots/gap" not in {v["space_origin"] for v in plots}
    for view in plots:
        values = [v[0] for e, rows in scalars.items() if e.startswith(f"/{view['space_origin']}/") for _, v in rows]
        assert np.isfinite(values).any(), view["display_name"]
    titles = {v["display_name"] for v in plots}
    assert {"a_x [m/s^2]: applied blue, plan orange", "e_d [m]", "e_a [rad]"} <= titles
    states = entities(path, "StateChange:state")["/states/manoeuvre"]
    assert [s[0] for _, s in states] == ["approach", "engaged"]


def test_the_platoon_leaders_manoeuvres_are_events(platoon):
    path, result, _ = platoon
    log = entities(path, "TextLog:text")["/events"]
    leader = [(t, text[0]) for t, text in log if text[0].startswith("[leader]")]
    assert leader == [
        (10.0, "[leader] leader brakes to 20 km/h at 2 m/s^2 (from 40 km/h)"),
        (35.0, "[leader] leader accelerates to 50 km/h at 1.5 m/s^2 (from 20 km/h)"),
    ]
    assert [e.kind for e in result.events].count("leader") == 2
    titles = {v["space_origin"]: v["display_name"] for v in plot_views(path)}
    assert titles["plots/kp"] == "kp [1/s^2]: f1 blue, f2 orange, f3 green"
    assert titles["plots/speed"] == "speed [m/s]: leader blue, f1 orange, f2 green, f3 pink"
    spatial = [v for v in views(path) if v["class_identifier"] == "2D"]
    close = next(v for v in spatial if v["display_name"] == "following the platoon")
    wide = next(v for v in spatial if " m around the platoon (" in v["display_name"])
    half = close["range"]["x_range"][1]
    assert wide["range"]["x_range"] == pytest.approx([-2 * half, 2 * half])
    assert 280.0 < 4 * half < 320.0  # about 300 m for report 004's platoon
