"""The task definitions match the observation classes and the controller registry."""

import dataclasses
import importlib

import pytest

from ego.control import CONTROLLERS, TASKS
from ego.scenarios import SCENARIOS


@pytest.mark.parametrize("name", list(TASKS))
def test_a_task_lists_exactly_its_observations_fields(name):
    task = TASKS[name]
    module, cls = task.observation.split(":")
    fields = [f.name for f in dataclasses.fields(getattr(importlib.import_module(module), cls))]
    assert [s.name for s in task.observes] == fields
    assert all(s.unit for s in task.observes + task.returns)
    assert len(task.returns) == 2


def test_every_task_has_controllers_and_every_scenario_a_task():
    assert set(CONTROLLERS) == set(TASKS)
    assert {cls.task for cls in SCENARIOS.values()} <= set(TASKS)
