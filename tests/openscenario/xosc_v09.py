"""A cut-in written in OpenSCENARIO 0.9 (VIRES' 0.9.1 schema, as the reference player's 0.9
examples write it) and the same scenario written by hand in 1.0, on straight3.xodr.

The ego drives lane -3 at s = 20 m, 20 m/s; Lead starts in the lane to its left (dLane 1),
10 m behind it, 5 m/s faster, and cuts in (a 2 s sinusoidal lane change to the ego's lane)
once it is more than 15 m ahead along the road; 1 s after its lane change ends it brakes at
5 m/s^2 (the 0.9 file writes the reference player's negative rate, -5) to a stop; the
scenario ends at 12 s. Both files use the vehicle catalog ``catalogs/Cars.xosc``, itself a 0.9
catalog.
"""

from __future__ import annotations

import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"

CATALOG_09 = """<?xml version="1.0" encoding="utf-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="0" revMinor="9" date="2026-11-29T10:00:00" description="cars" author="ego tests"/>
  <Catalog name="Cars">
    <Vehicle name="car" category="car">
      <ParameterDeclaration>
        <Parameter name="$Length" type="double" value="4.5"/>
      </ParameterDeclaration>
      <BoundingBox>
        <Center x="1.4" y="0" z="0.75"/>
        <Dimension width="1.8" length="$Length" height="1.5"/>
      </BoundingBox>
      <Performance maxSpeed="55" maxDeceleration="9" mass="1500" maxAcceleration="4"/>
      <Axles>
        <Front maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/>
        <Rear maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/>
      </Axles>
      <Properties>
        <Property name="colour" value="white"/>
      </Properties>
    </Vehicle>
  </Catalog>
</OpenSCENARIO>
"""

CATALOG_10 = """<?xml version="1.0" encoding="utf-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2026-11-29T10:00:00" description="cars" author="ego tests"/>
  <Catalog name="Cars10">
    <Vehicle name="car" vehicleCategory="car">
      <ParameterDeclarations>
        <ParameterDeclaration name="Length" parameterType="double" value="4.5"/>
      </ParameterDeclarations>
      <BoundingBox>
        <Center x="1.4" y="0" z="0.75"/>
        <Dimensions width="1.8" length="$Length" height="1.5"/>
      </BoundingBox>
      <Performance maxSpeed="55" maxDeceleration="9" maxAcceleration="4"/>
    </Vehicle>
  </Catalog>
</OpenSCENARIO>
"""

V09 = """<?xml version="1.0" encoding="utf-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="0" revMinor="9" date="2026-11-29T10:00:00" description="cut-in 0.9" author="ego tests"/>
  <ParameterDeclaration>
    <Parameter name="$EgoSpeed" type="double" value="20"/>
    <Parameter name="$Behind" type="double" value="-10"/>
    <Parameter name="$Rate" type="double" value="-5"/>
  </ParameterDeclaration>
  <Catalogs>
    <VehicleCatalog>
      <Directory path="catalogs"/>
    </VehicleCatalog>
    <DriverCatalog/>
    <RouteCatalog/>
  </Catalogs>
  <RoadNetwork>
    <Logics filepath="straight3.xodr"/>
    <SceneGraph filepath="straight3.osgb"/>
  </RoadNetwork>
  <Entities>
    <Object name="Ego">
      <CatalogReference catalogName="Cars" entryName="car"/>
      <Properties>
        <Property name="control" value="internal"/>
      </Properties>
    </Object>
    <Object name="Lead">
      <CatalogReference catalogName="Cars" entryName="car"/>
      <Controller>
        <Driver name="calm">
          <Description weight="80" height="1.8" eyeDistance="0.065" age="40" sex="female">
            <Properties/>
          </Description>
        </Driver>
      </Controller>
    </Object>
  </Entities>
  <Storyboard>
    <Init>
      <Actions>
        <Private object="Ego">
          <Action>
            <Position>
              <Lane roadId="0" laneId="-3" offset="0" s="20"/>
            </Position>
          </Action>
          <Action name="EgoSpeed">
            <Longitudinal>
              <Speed>
                <Dynamics shape="step"/>
                <Target>
                  <Absolute value="$EgoSpeed"/>
                </Target>
              </Speed>
            </Longitudinal>
          </Action>
        </Private>
        <Private object="Lead">
          <Action>
            <Position>
              <RelativeLane object="Ego" dLane="1" ds="$Behind"/>
            </Position>
          </Action>
          <Action>
            <Longitudinal>
              <Speed>
                <Dynamics shape="step"/>
                <Target>
                  <Relative object="Ego" value="5" valueType="delta" continuous="false"/>
                </Target>
              </Speed>
            </Longitudinal>
          </Action>
        </Private>
      </Actions>
    </Init>
    <Story name="CutInStory" owner="Lead">
      <Act name="CutInAct">
        <Sequence name="CutInSequence" numberOfExecutions="1">
          <Actors>
            <Entity name="$owner"/>
          </Actors>
          <Maneuver name="CutInManeuver">
            <Event name="CutIn" priority="overwrite">
              <Action name="CutInAction">
                <Private>
                  <Lateral>
                    <LaneChange>
                      <Dynamics shape="sinusoidal" time="2"/>
                      <Target>
                        <Relative object="Ego" value="0"/>
                      </Target>
                    </LaneChange>
                  </Lateral>
                </Private>
              </Action>
              <StartConditions>
                <ConditionGroup>
                  <Condition name="Ahead" delay="0" edge="rising">
                    <ByEntity>
                      <TriggeringEntities rule="any">
                        <Entity name="$owner"/>
                      </TriggeringEntities>
                      <EntityCondition>
                        <RelativeDistance entity="Ego" type="longitudinal" value="15" freespace="false" rule="greater_than"/>
                      </EntityCondition>
                    </ByEntity>
                  </Condition>
                </ConditionGroup>
              </StartConditions>
            </Event>
            <Event name="Brake" priority="overwrite">
              <Action name="BrakeAction">
                <Private>
                  <Longitudinal>
                    <Speed>
                      <Dynamics shape="linear" rate="$Rate"/>
                      <Target>
                        <Absolute value="0"/>
                      </Target>
                    </Speed>
                  </Longitudinal>
                </Private>
              </Action>
              <StartConditions>
                <ConditionGroup>
                  <Condition name="AfterCutIn" delay="1" edge="rising">
                    <ByState>
                      <AfterTermination type="event" name="CutIn" rule="end"/>
                    </ByState>
                  </Condition>
                </ConditionGroup>
              </StartConditions>
            </Event>
          </Maneuver>
        </Sequence>
        <Conditions>
          <Start>
            <ConditionGroup>
              <Condition name="ActStart" delay="0" edge="any">
                <ByValue>
                  <SimulationTime value="0" rule="greater_than"/>
                </ByValue>
              </Condition>
            </ConditionGroup>
          </Start>
        </Conditions>
      </Act>
    </Story>
    <EndConditions>
      <ConditionGroup>
        <Condition name="End" delay="0" edge="rising">
          <ByValue>
            <SimulationTime value="12" rule="greater_than"/>
          </ByValue>
        </Condition>
      </ConditionGroup>
    </EndConditions>
  </Storyboard>
</OpenSCENARIO>
"""

V10 = """<?xml version="1.0" encoding="utf-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2026-11-29T10:00:00" description="cut-in 1.0" author="ego tests"/>
  <ParameterDeclarations>
    <ParameterDeclaration name="EgoSpeed" parameterType="double" value="20"/>
    <ParameterDeclaration name="Behind" parameterType="double" value="-10"/>
    <ParameterDeclaration name="Rate" parameterType="double" value="5"/>
  </ParameterDeclarations>
  <CatalogLocations>
    <VehicleCatalog><Directory path="catalogs"/></VehicleCatalog>
  </CatalogLocations>
  <RoadNetwork><LogicFile filepath="straight3.xodr"/></RoadNetwork>
  <Entities>
    <ScenarioObject name="Ego"><CatalogReference catalogName="Cars10" entryName="car"/></ScenarioObject>
    <ScenarioObject name="Lead"><CatalogReference catalogName="Cars10" entryName="car"/></ScenarioObject>
  </Entities>
  <Storyboard>
    <Init>
      <Actions>
        <Private entityRef="Ego">
          <PrivateAction><TeleportAction><Position>
            <LanePosition roadId="0" laneId="-3" offset="0" s="20"/>
          </Position></TeleportAction></PrivateAction>
          <PrivateAction><LongitudinalAction><SpeedAction>
            <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
            <SpeedActionTarget><AbsoluteTargetSpeed value="$EgoSpeed"/></SpeedActionTarget>
          </SpeedAction></LongitudinalAction></PrivateAction>
        </Private>
        <Private entityRef="Lead">
          <PrivateAction><TeleportAction><Position>
            <RelativeLanePosition entityRef="Ego" dLane="1" ds="$Behind"/>
          </Position></TeleportAction></PrivateAction>
          <PrivateAction><LongitudinalAction><SpeedAction>
            <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
            <SpeedActionTarget>
              <RelativeTargetSpeed entityRef="Ego" value="5" speedTargetValueType="delta" continuous="false"/>
            </SpeedActionTarget>
          </SpeedAction></LongitudinalAction></PrivateAction>
        </Private>
      </Actions>
    </Init>
    <Story name="CutInStory">
      <Act name="CutInAct">
        <ManeuverGroup name="CutInSequence" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="Lead"/></Actors>
          <Maneuver name="CutInManeuver">
            <Event name="CutIn" priority="overwrite">
              <Action name="CutInAction"><PrivateAction><LateralAction><LaneChangeAction>
                <LaneChangeActionDynamics dynamicsShape="sinusoidal" value="2" dynamicsDimension="time"/>
                <LaneChangeTarget><RelativeTargetLane entityRef="Ego" value="0"/></LaneChangeTarget>
              </LaneChangeAction></LateralAction></PrivateAction></Action>
              <StartTrigger><ConditionGroup>
                <Condition name="Ahead" delay="0" conditionEdge="rising"><ByEntityCondition>
                  <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Lead"/></TriggeringEntities>
                  <EntityCondition>
                    <RelativeDistanceCondition entityRef="Ego" relativeDistanceType="longitudinal" value="15"
                        freespace="false" rule="greaterThan"/>
                  </EntityCondition>
                </ByEntityCondition></Condition>
              </ConditionGroup></StartTrigger>
            </Event>
            <Event name="Brake" priority="overwrite">
              <Action name="BrakeAction"><PrivateAction><LongitudinalAction><SpeedAction>
                <SpeedActionDynamics dynamicsShape="linear" value="$Rate" dynamicsDimension="rate"/>
                <SpeedActionTarget><AbsoluteTargetSpeed value="0"/></SpeedActionTarget>
              </SpeedAction></LongitudinalAction></PrivateAction></Action>
              <StartTrigger><ConditionGroup>
                <Condition name="AfterCutIn" delay="1" conditionEdge="rising"><ByValueCondition>
                  <StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="CutIn"
                      state="endTransition"/>
                </ByValueCondition></Condition>
              </ConditionGroup></StartTrigger>
            </Event>
          </Maneuver>
        </ManeuverGroup>
        <StartTrigger><ConditionGroup>
          <Condition name="ActStart" delay="0" conditionEdge="risingOrFalling"><ByValueCondition>
            <SimulationTimeCondition value="0" rule="greaterThan"/>
          </ByValueCondition></Condition>
        </ConditionGroup></StartTrigger>
      </Act>
    </Story>
    <StopTrigger><ConditionGroup>
      <Condition name="End" delay="0" conditionEdge="rising"><ByValueCondition>
        <SimulationTimeCondition value="12" rule="greaterThan"/>
      </ByValueCondition></Condition>
    </ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""


def write(tmp: Path, text: str = V09, name: str = "cut_in_09.xosc") -> Path:
    """``text`` at ``tmp/name`` beside straight3.xodr and both catalogs; its path."""
    shutil.copy(SHIPPED / "straight3.xodr", tmp / "straight3.xodr")
    (tmp / "catalogs").mkdir(exist_ok=True)
    (tmp / "catalogs" / "Cars.xosc").write_text(CATALOG_09)
    (tmp / "catalogs" / "Cars10.xosc").write_text(CATALOG_10)
    path = tmp / name
    path.write_text(text)
    return path


def sub(old: str, new: str, text: str = V09) -> str:
    """``text`` with its one ``old`` replaced by ``new``."""
    assert text.count(old) == 1, old
    return text.replace(old, new)
