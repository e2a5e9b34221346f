"""scripts/corpus_run.py's target set: the corpus issue's "examples on roads without city
junction networks and without trailers", decided from each file, its road and its catalogs
(hand-written files in a copy of the reference player's folder layout)."""

from __future__ import annotations

from pathlib import Path

import pytest
from xosc_scenes import script

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"


corpus_run = script("corpus_run")


def junction(kind: str, incoming: list[int]) -> str:
    conns = "".join(
        f'<connection id="{i}" incomingRoad="{r}" connectingRoad="{10 + i}" contactPoint="start"/>'
        for i, r in enumerate(incoming)
    )
    return f'<junction id="4" {kind}>{conns}</junction>'


def xodr(extra: str = "") -> str:
    return f'<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="6"/>{extra}</OpenDRIVE>'


CATALOG = """<?xml version="1.0"?><OpenSCENARIO><FileHeader revMajor="1" revMinor="1" date="x" description="" author=""/>
<Catalog name="VehicleCatalog">
  <Vehicle name="car" vehicleCategory="car">
    <ParameterDeclarations><ParameterDeclaration name="TrailerRef" parameterType="string" value=""/></ParameterDeclarations>
    <TrailerHitch dx="-1.2"/><Trailer><EntityRef entityRef="$TrailerRef"/></Trailer>
  </Vehicle>
  <Vehicle name="truck" vehicleCategory="truck">
    <Trailer><CatalogReference catalogName="VehicleCatalog" entryName="box"/></Trailer>
  </Vehicle>
  <Vehicle name="box" vehicleCategory="trailer"/>
</Catalog></OpenSCENARIO>"""


def scenario(road: str | None, entities: str, story: str = "") -> str:
    net = f'<LogicFile filepath="{road}"/>' if road else '<SceneGraphFile filepath="x.osgb"/>'
    return f"""<?xml version="1.0"?><OpenSCENARIO><FileHeader revMajor="1" revMinor="1" date="x" description="" author=""/>
<ParameterDeclarations><ParameterDeclaration name="Road" parameterType="string" value="../xodr/plain.xodr"/>
</ParameterDeclarations>
<CatalogLocations><VehicleCatalog><Directory path="../xosc/Catalogs/Vehicles"/></VehicleCatalog></CatalogLocations>
<RoadNetwork>{net}</RoadNetwork><Entities>{entities}</Entities><Storyboard>{story}</Storyboard></OpenSCENARIO>"""


def obj(name: str, entry: str, assign: str = "") -> str:
    params = f'<ParameterAssignments><ParameterAssignment parameterRef="TrailerRef" value="{assign}"/></ParameterAssignments>'
    return (
        f'<ScenarioObject name="{name}"><CatalogReference catalogName="VehicleCatalog" entryName="{entry}">'
        f"{params if assign else ''}</CatalogReference></ScenarioObject>"
    )


@pytest.fixture
def corpus(tmp_path: Path) -> Path:
    (tmp_path / "xodr").mkdir()
    (tmp_path / "xodr" / "plain.xodr").write_text(xodr())
    (tmp_path / "xodr" / "merge.xodr").write_text(xodr(junction('type="direct"', [1, 2, 3])))
    (tmp_path / "xodr" / "town.xodr").write_text(xodr(junction("", [0, 1, 2, 3])))
    (tmp_path / "xodr" / "tee.xodr").write_text(xodr(junction("", [0, 0, 1])))
    (tmp_path / "xosc" / "Catalogs" / "Vehicles").mkdir(parents=True)
    (tmp_path / "xosc" / "Catalogs" / "Vehicles" / "VehicleCatalog.xosc").write_text(CATALOG)
    return tmp_path / "xosc"


CASES = {
    # in the target set
    "plain": ("../xodr/plain.xodr", obj("Ego", "car"), None),
    "parameter road": ("$Road", obj("Ego", "car"), None),
    "direct junction (a merge)": ("../xodr/merge.xodr", obj("Ego", "car"), None),
    "two roads into a junction": ("../xodr/tee.xodr", obj("Ego", "car"), None),
    "found by name": ("C:/Users/someone/plain.xodr", obj("Ego", "car"), None),
    # left out
    "intersection": (
        "../xodr/town.xodr",
        obj("Ego", "car"),
        "city junction network: town.xodr (junction 4 joins 4 roads)",
    ),
    "city map by name": (
        "../xodr/multi_intersections.xodr",
        obj("Ego", "car"),
        "city junction network: multi_intersections.xodr (by name)",
    ),
    "hitch with a trailer assigned": (
        "../xodr/plain.xodr",
        obj("Ego", "car") + obj("Car", "car", "Ego"),
        "trailer: entity 'Car': 'car' tows 'Ego'",
    ),
    "tows from the catalog": ("../xodr/plain.xodr", obj("T", "truck"), "trailer: entity 'T': 'truck' tows 'box'"),
    "is a trailer": ("../xodr/plain.xodr", obj("B", "box"), "trailer: entity 'B': 'box' is a trailer"),
    "no road": (None, obj("Ego", "car"), "no road: the file names no road file"),
}


@pytest.mark.parametrize("case", CASES)
def test_exclusion(corpus, case):
    road, entities, why = CASES[case]
    path = corpus / "s.xosc"
    path.write_text(scenario(road, entities))
    assert corpus_run.exclusion(path) == why


def test_connected_trailer_and_unavailable_road(corpus):
    path = corpus / "s.xosc"
    path.write_text(scenario("../xodr/plain.xodr", obj("Ego", "car"), "<Story><ConnectTrailerAction/></Story>"))
    assert corpus_run.exclusion(path) == "trailer: the storyboard connects a trailer (ConnectTrailerAction)"
    path.write_text(scenario("../xodr/elsewhere.xodr", obj("Ego", "car")))
    assert corpus_run.exclusion(path) == f"road unavailable: ../xodr/elsewhere.xodr is nowhere under {corpus.parent}"


def variation(scenario: str) -> str:
    return f"""<?xml version="1.0"?><OpenSCENARIO><FileHeader revMajor="1" revMinor="2" date="x" description="" author=""/>
<ParameterValueDistribution><ScenarioFile filepath="{scenario}"/><Deterministic>
<DeterministicSingleParameterDistribution parameterName="Road"><DistributionSet><Element value="../xodr/plain.xodr"/>
</DistributionSet></DeterministicSingleParameterDistribution></Deterministic></ParameterValueDistribution></OpenSCENARIO>"""


def test_summary_line(corpus, capsys):
    """A real run of the script: a refused target file, a file left out with its reason, and
    variation files (``ego sweep``) in the set as the scenario files they vary."""
    (corpus / "a_target.xosc").write_text(scenario("$Road", obj("Ego", "car")))
    (corpus / "b_town.xosc").write_text(scenario("../xodr/town.xodr", obj("Ego", "car")))
    (corpus / "c_vary.xosc").write_text(variation("a_target.xosc"))
    (corpus / "d_vary.xosc").write_text(variation("b_town.xosc"))
    assert corpus_run.main([str(corpus), "--timeout", "60"]) == 0
    out = capsys.readouterr().out
    assert "| a_target.xosc | 2 |" in out and "| c_vary.xosc | 2 |" in out
    assert "2 files: 0 ran (0 exit 0), 2 refused cleanly, 0 crashed" in out
    assert "ego list agrees with ego run on 2 of 2 files" in out
    tail = out[out.index("2 variation files") :].splitlines()
    assert tail == [
        "2 variation files: 0 swept",
        "",
        "left out of the target set (2 files):",
        "- b_town.xosc: city junction network: town.xodr (junction 4 joins 4 roads)",
        "- d_vary.xosc: varies b_town.xosc: city junction network: town.xodr (junction 4 joins 4 roads)",
        "0 of 2 target files run (0 %)",
    ]


def test_list_agrees_with_what_the_run_did():
    """``ego list FILE --json`` is asked for real: a shipped file it reads as supported agrees
    with a run that ran and not with one refused (or crashed)."""
    path = Path(__file__).resolve().parents[2] / "scenarios" / "openscenario" / "cut_in.xosc"
    assert corpus_run.list_agrees(path, {"verdict": "ran", "first": ""})
    assert not corpus_run.list_agrees(path, {"verdict": "refused", "first": "cut_in.xosc:1: no"})
    assert not corpus_run.list_agrees(path, {"verdict": "crashed", "first": "exit 139"})
