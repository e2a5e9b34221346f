"""Finding a scenario's road and catalogs where real files put them (ego.openscenario.files):
the path as written relative to the scenario, then the file's name (and the path as written)
in each search folder - the scenario's folder, ``--path DIR``, ``$EGO_PATH`` - with a note on
stderr; a file found nowhere is one line naming every place looked. Real SUMO runs."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

from ego.cli import main
from ego.openscenario.files import SEARCH_ENV
from ego.openscenario.loader import load

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"
EB = (SHIPPED / "emergency_brake.xosc").read_text()
CUT_IN = (SHIPPED / "cut_in.xosc").read_text()


@pytest.fixture(autouse=True)
def _env(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))
    monkeypatch.delenv(SEARCH_ENV, raising=False)


def _scenario(folder: Path, road: str, text: str = EB) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "case.xosc"
    path.write_text(text.replace('filepath="straight3.xodr"', f'filepath="{road}"'))
    return path


def _roads(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(SHIPPED / "straight3.xodr", folder / "straight3.xodr")
    return folder


def test_road_written_for_another_folder_is_found_by_name_in_a_path_folder(tmp_path, capsys):
    """esmini's aeb_cut_in.xosc names '../resources/xodr/curve_r100.xodr' (relative to its bin
    folder): with --path the road's folder, ego finds the file by its name and says so, once."""
    roads = _roads(tmp_path / "resources" / "xodr")
    path = _scenario(tmp_path / "resources" / "xosc", "../resources/xodr/straight3.xodr")
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 2
    err = capsys.readouterr().err
    written = Path(os.path.abspath(path.parent / "../resources/xodr/straight3.xodr"))
    assert err == (
        f"ego: error: {path}:{_line(path, 'LogicFile')}: road file '../resources/xodr/straight3.xodr' not found "
        f"(looked for {written}, {path.parent / 'straight3.xodr'})\n"
    )
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1", "--path", str(roads)]) == 0
    err = capsys.readouterr().err
    assert err == (
        f"ego: warning: {path}: road file '../resources/xodr/straight3.xodr' is not at {written}; "
        f"found as {roads / 'straight3.xodr'} (see docs/openscenario.md)\n"
    )


def test_a_path_folder_also_takes_the_path_as_written(tmp_path, capsys):
    """--path DIR tries DIR/<the path as written> before DIR/<its name> (as esmini does with its
    bin folder): '../resources/xodr/x.xodr' from tmp/resources/xosc, --path tmp/bin."""
    _roads(tmp_path / "resources" / "xodr")
    (tmp_path / "bin").mkdir()
    path = _scenario(tmp_path / "resources" / "xosc", "../resources/xodr/straight3.xodr")
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1", "--path", str(tmp_path / "bin")]) == 0
    assert f"found as {tmp_path / 'resources' / 'xodr' / 'straight3.xodr'} " in capsys.readouterr().err


@pytest.mark.parametrize("written", ["C:/Users/someone/Downloads/straight3.xodr", "C:\\Users\\x\\straight3.xodr"])
def test_a_windows_drive_path_is_the_file_name_in_the_scenario_folder(tmp_path, capsys, written):
    """esmini's car_walk.xosc and i496.xosc name roads on their author's disk: the name in the
    scenario's own folder is found (no crash on a drive letter or backslashes)."""
    path = _scenario(_roads(tmp_path), written)
    model = load(path)
    assert model.road == (tmp_path / "straight3.xodr").resolve()
    assert "is not at the path as written (a Windows drive); found as" in capsys.readouterr().err


def test_ego_path_environment_variable(tmp_path, monkeypatch, capsys):
    """$EGO_PATH (folders separated by the OS's separator) is searched after --path."""
    roads = _roads(tmp_path / "roads")
    path = _scenario(tmp_path / "s", "elsewhere/straight3.xodr")
    monkeypatch.setenv(SEARCH_ENV, f"{tmp_path / 'nothing'}:{roads}")
    assert load(path).road == (roads / "straight3.xodr").resolve()
    capsys.readouterr()
    # list and sweep read it too (a sweep's workers inherit the command's search folders)
    monkeypatch.delenv(SEARCH_ENV)
    assert main(["list", str(path), "--json", "--path", str(roads)]) == 0
    assert json.loads(capsys.readouterr().out)["supported"] is True


def test_sweep_workers_find_the_road_through_path(tmp_path, capfd):
    """--path reaches the worker processes; the note is printed once, not once a worker."""
    roads = _roads(tmp_path / "roads")
    path = _scenario(tmp_path / "s", "elsewhere/straight3.xodr")
    spec = tmp_path / "spec.toml"
    spec.write_text(f'scenario = "{path}"\ncontrollers = ["pid"]\n[set]\nduration = 1.0\n[grid]\nLeadGap = [30, 40]\n')
    out = tmp_path / "out"
    assert main(["sweep", str(spec), "--out", str(out), "--jobs", "2", "--path", str(roads)]) == 0
    import pandas as pd

    assert sorted(pd.read_parquet(out / "results.parquet")["status"]) == ["completed", "completed"]
    assert capfd.readouterr().err.count("ego: warning: ") == 1


def test_a_road_found_nowhere_lists_every_place(tmp_path, capsys):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    path = _scenario(tmp_path / "s", "../xodr/nowhere.xodr")
    assert main(["run", str(path), "-c", "pid", "--path", str(a), "--path", str(b)]) == 2
    places = [
        tmp_path / "xodr" / "nowhere.xodr",
        path.parent / "nowhere.xodr",
        tmp_path / "xodr" / "nowhere.xodr",  # a/../xodr: the same place, listed once
        a / "nowhere.xodr",
        b / "nowhere.xodr",
    ]
    listed = ", ".join(dict.fromkeys(str(p) for p in places))
    assert capsys.readouterr().err == (
        f"ego: error: {path}:{_line(path, 'LogicFile')}: road file '../xodr/nowhere.xodr' not found "
        f"(looked for {listed})\n"
    )


def test_bad_path_option_is_one_line(tmp_path, capsys):
    path = _scenario(_roads(tmp_path), "straight3.xodr")
    assert main(["run", str(path), "-c", "pid", "--path", str(tmp_path / "missing")]) == 2
    assert capsys.readouterr().err == f"ego: error: bad --path '{tmp_path / 'missing'}': not a folder\n"


def test_catalog_in_a_folder_that_does_not_exist_is_found_by_name(tmp_path, capsys):
    """esmini's auto_light.xosc names its vehicle catalog folder '../xosc/Vehicles', which does
    not exist: --path the folder holding VehicleCatalog.xosc finds it (and so does a --path
    holding the folder as written)."""
    cats = tmp_path / "Catalogs" / "Vehicles"
    cats.mkdir(parents=True)
    shutil.copy(SHIPPED / "catalogs" / "VehicleCatalog.xosc", cats / "VehicleCatalog.xosc")
    text = CUT_IN.replace('<Directory path="catalogs"/>', '<Directory path="../xosc/Vehicles"/>')
    assert text != CUT_IN
    folder = _roads(tmp_path / "xosc")
    path = folder / "cut.xosc"
    path.write_text(text)
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 2
    err = capsys.readouterr().err
    assert "catalog 'VehicleCatalog' not found (looked for " in err and err.count("\n") == 1
    assert str(tmp_path / "xosc" / "Vehicles" / "VehicleCatalog.xosc") in err  # the folder as written
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1", "--path", str(cats)]) == 0
    assert f"found as {cats / 'VehicleCatalog.xosc'} " in capsys.readouterr().err
    # once the folder as written exists, it is used without a note
    (tmp_path / "xosc" / "Vehicles").mkdir()
    shutil.copy(cats / "VehicleCatalog.xosc", tmp_path / "xosc" / "Vehicles" / "VehicleCatalog.xosc")
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 0
    assert capsys.readouterr().err == ""  # as written: no note


def test_concrete_file_names_the_road_where_it_was_found(tmp_path, capsys):
    roads = _roads(tmp_path / "roads")
    path = _scenario(tmp_path / "s", "C:/elsewhere/straight3.xodr")
    out = tmp_path / "out" / "row.xosc"
    out.parent.mkdir()
    assert main(["concrete", str(path), "--set", "LeadGap=35", "--out", str(out), "--path", str(roads)]) == 0
    capsys.readouterr()
    assert 'filepath="../roads/straight3.xodr"' in out.read_text()
    assert main(["run", str(out), "-c", "pid", "--set", "duration=1"]) == 0  # stands alone, no --path


def _line(path: Path, marker: str) -> int:
    text = path.read_text()
    return text.count("\n", 0, text.index(marker)) + 1


def test_a_distributions_scenario_file_is_found_the_same_way(tmp_path, capsys):
    """A ParameterValueDistribution's ScenarioFile written for another folder: one line naming
    the places looked; found by name through --path (ego list describes the variation)."""
    templates = _roads(tmp_path / "templates")
    _scenario(templates, "straight3.xodr")
    var = tmp_path / "variations" / "var.xosc"
    var.parent.mkdir()
    var.write_text(
        '<?xml version="1.0"?>\n<OpenSCENARIO>\n<FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" '
        'description="v" author="t"/>\n<ParameterValueDistribution>\n<ScenarioFile filepath="C:/work/case.xosc"/>\n'
        '<Deterministic><DeterministicSingleParameterDistribution parameterName="LeadGap"><DistributionSet>'
        '<Element value="30"/><Element value="40"/></DistributionSet></DeterministicSingleParameterDistribution>'
        "</Deterministic>\n</ParameterValueDistribution>\n</OpenSCENARIO>\n"
    )
    assert main(["list", str(var)]) == 2
    assert capsys.readouterr().err == (
        f"ego: error: {var}:5: ScenarioFile 'C:/work/case.xosc' not found (looked for {var.parent / 'case.xosc'})\n"
    )
    assert main(["list", str(var), "--path", str(templates)]) == 0
    out, err = capsys.readouterr()
    assert "combinations  2" in out and f"found as {templates / 'case.xosc'} " in err


def test_dot_dot_after_a_linked_folder_goes_where_the_file_system_goes(tmp_path, capsys):
    """The path as written keeps the file system's meaning: '../xodr/...' from a scenario folder
    that is a symbolic link is the link target's sibling (as before the search folders)."""
    _roads(tmp_path / "real" / "xodr")
    _scenario(tmp_path / "real" / "xosc", "../xodr/straight3.xodr")
    (tmp_path / "link").symlink_to(tmp_path / "real" / "xosc")
    assert load(tmp_path / "link" / "case.xosc").road == (tmp_path / "real" / "xodr" / "straight3.xodr").resolve()
    assert capsys.readouterr().err == ""


def test_a_catalog_directory_that_is_the_catalog_file_itself(tmp_path, capsys):
    """esmini's 0.9 examples write Directory path="../xosc/Catalogs/VehicleCatalog", naming the
    catalog file (no extension), not a folder: the file whose <Catalog name> is the reference's."""
    folder = _roads(tmp_path / "xosc")
    (folder / "Catalogs").mkdir()
    shutil.copy(SHIPPED / "catalogs" / "VehicleCatalog.xosc", folder / "Catalogs" / "VehicleCatalog")
    path = folder / "cut.xosc"
    path.write_text(CUT_IN.replace('<Directory path="catalogs"/>', '<Directory path="Catalogs/VehicleCatalog"/>'))
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 0
    assert capsys.readouterr().err == ""
