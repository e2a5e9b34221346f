"""The simulator boundary: backends by name with declared capabilities, options as data,
one error type for every backend, and no libsumo outside ego/sumo."""

import ast
from pathlib import Path

import pytest

from ego.params import ConfigError
from ego.runner import RunSpec, run
from ego.sim import BACKENDS, SimError, check_options
from ego.sim.protocol import TrafficSim
from ego.sumo.bridge import SumoBridge, SumoError

PACKAGE = Path(__file__).resolve().parents[2] / "ego"


def test_both_backends_are_registered_with_their_capabilities():
    sumo, he = BACKENDS["sumo"], BACKENDS["highway-env"]
    assert sumo.capabilities.sublane and sumo.capabilities.any_network and not sumo.capabilities.video
    assert he.capabilities.video and not he.capabilities.sublane and he.options == ("video",)
    assert all(b.capabilities.scripted_actors for b in BACKENDS.values())


def test_options_are_checked_against_the_backend():
    check_options("sumo", {})
    with pytest.raises(ConfigError, match="--video needs --backend highway-env"):
        check_options("sumo", {"video": "run.gif"})
    with pytest.raises(ConfigError, match="bad backend option 'zoom'"):
        check_options("sumo", {"zoom": 2})
    with pytest.raises(ConfigError, match="bad value for --backend: 'carla'"):
        check_options("carla", {})


def test_sumo_errors_are_sim_errors_and_both_bridges_have_the_protocol():
    from ego.highway_env.bridge import HighwayEnvBridge

    assert issubclass(SumoError, SimError)
    for bridge in (SumoBridge, HighwayEnvBridge):
        missing = [
            name
            for name in dir(TrafficSim)
            if not name.startswith("_") and name != "controlled" and not hasattr(bridge, name)
        ]
        assert missing == [], bridge.__name__


def test_highway_env_raises_sim_errors_not_sumo_errors():
    source = (PACKAGE / "highway_env" / "bridge.py").read_text()
    assert "SumoError" not in source and "raise SimError(" in source


def test_no_libsumo_import_outside_ego_sumo():
    offenders = []
    for path in PACKAGE.rglob("*.py"):
        if path.parent.name == "sumo":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            if any(n.split(".")[0] == "libsumo" for n in names):
                offenders.append(str(path.relative_to(PACKAGE)))
    assert offenders == []


def test_the_sim_package_imports_nothing_above_it():
    # plugins is a foundation module (tests/test_layers.py): the entry-point groups
    for path in (PACKAGE / "sim").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("ego."):
                assert node.module.split(".")[1] in ("sim", "models", "params", "plugins"), (path.name, node.module)


@pytest.mark.sumo
def test_backend_options_travel_as_data(tmp_path):
    with pytest.raises(ConfigError, match="--video needs --backend highway-env"):
        run(RunSpec("cut-in", "pid", backend_options={"video": str(tmp_path / "v.gif")}))
    assert not (tmp_path / "v.gif").exists()


def test_backend_choices_are_read_when_the_parser_is_built():
    """A backend registered after ego.cli.parser is imported is a --backend choice of every
    parser built afterwards (the registry is read when the parser is built)."""
    from ego.cli.parser import parser
    from ego.sim.registry import Backend, Capabilities, register

    before = parser()
    register(Backend("late-road", "ego.sumo.bridge:make_sim", Capabilities(any_network=True)))
    try:
        args = parser().parse_args(["run", "emergency-brake", "-c", "pid", "--backend", "late-road"])
        assert args.backend == "late-road"
        with pytest.raises(ConfigError, match="invalid choice: 'late-road'"):
            before.parse_args(["run", "emergency-brake", "-c", "pid", "--backend", "late-road"])
    finally:
        BACKENDS.pop("late-road")


def test_check_needs_names_the_scenario_the_backend_and_what_it_lacks():
    from ego.sim.registry import check_needs

    assert check_needs("scenario curve", ("any_network",), "sumo").name == "sumo"
    with pytest.raises(ConfigError) as err:
        check_needs("scenario curve", ("any_network", "scripted_actors"), "highway-env")
    assert str(err.value) == (
        "bad value for --backend: 'highway-env' (scenario curve needs any_network; backend highway-env lacks it)"
    )
