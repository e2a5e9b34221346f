"""scripts/alks_run.py on a hand-written copy in the R157 repository's layout: a template in
``Scenarios/`` (its road beside it) run with ``ego run``, a variation file in
``LogicalScenarios/`` whose template in ``ConcreteScenarios/`` names a road that folder lacks
(found in ``Scenarios/`` as the script's ``--path`` says), swept whole with its value constraint
applied first; the count line."""

from __future__ import annotations

import json
import shutil

from xosc_scenes import SHIPPED, scene, script, sim_time

GAP = (
    '<ParameterDeclaration name="Gap" parameterType="double" value="150">'
    '<ConstraintGroup><ValueConstraint rule="greaterThan" value="100"/></ConstraintGroup></ParameterDeclaration>'
)
VARIATION = """<?xml version="1.0"?>
<OpenSCENARIO><FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="v" author="ego tests"/>
<ParameterValueDistribution><ScenarioFile filepath="./ConcreteScenarios/ALKS_Scenario_4.0_1_Tiny_TEMPLATE.xosc"/>
<Deterministic><DeterministicSingleParameterDistribution parameterName="Gap"><DistributionSet>
<Element value="100"/><Element value="150"/><Element value="200"/></DistributionSet>
</DeterministicSingleParameterDistribution></Deterministic></ParameterValueDistribution></OpenSCENARIO>
"""


def test_templates_run_and_variations_sweep_with_the_repositorys_folders(tmp_path, capsys):
    alks_run = script("alks_run")
    copy = tmp_path / "OSC-ALKS-scenarios"
    (copy / "Scenarios").mkdir(parents=True)
    (copy / "LogicalScenarios" / "ConcreteScenarios").mkdir(parents=True)
    stop = f"<StopTrigger><ConditionGroup>{sim_time(1.0)}</ConditionGroup></StopTrigger>"
    path = scene(tmp_path, [], params=GAP, stop=stop, at={"C": (-3, "$Gap", 15.0)})
    template = path.read_text()
    (copy / "Scenarios" / "ALKS_Scenario_4.0_1_Tiny_TEMPLATE.xosc").write_text(template)
    (copy / "Scenarios" / "ALKS_Scenario_4.0_1_Tiny_TEMPLATE_esmini.xosc").write_text(template)  # left out
    shutil.copy(SHIPPED / "straight3.xodr", copy / "Scenarios" / "straight3.xodr")
    (copy / "LogicalScenarios" / "ConcreteScenarios" / "ALKS_Scenario_4.0_1_Tiny_TEMPLATE.xosc").write_text(template)
    (copy / "LogicalScenarios" / "ALKS_Scenario_4.0_1_Tiny_Variation.xosc").write_text(VARIATION)
    assert [p.name for p in alks_run.templates(copy)] == ["ALKS_Scenario_4.0_1_Tiny_TEMPLATE.xosc"]
    out = tmp_path / "sweeps"
    code = alks_run.main([str(copy), "--out", str(out), "--json", str(tmp_path / "rows.json"), "--jobs", "1"])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "2 of 2 run (1 templates with ego run, 1 variation files with ego sweep); 0 refused, 0 crashed" in text
    rows = json.loads((tmp_path / "rows.json").read_text())
    assert [r["verdict"] for r in rows] == ["ran", "ran"]
    # 3 combinations, the Gap of 100 discarded by greaterThan 100, the other 2 run (a sample of 4)
    assert rows[1]["combinations"] == [3, 1, 2]
    assert rows[1]["sample"].startswith("2 completed")
