"""Any ego controller as a policy on the ``EgoState`` observation.

``ControllerPolicy(controller, env)`` turns a controller (a name of the env's task, as ``ego run
-c`` takes, or a built :class:`ego.control.Controller`) into a callable observation -> action
for that env: it rebuilds the controller's observation from the vector's named fields, steps
the controller and maps its command onto the env's action type. With ``EgoAction`` the
round trip is exact (float64 both ways), so driving the env with the policy reproduces
``ego run`` (same metrics); with ``ContinuousAction`` the command is scaled into [-1, 1] and
clipped, so commands beyond the ranges are lost.

In the platoon the policy drives the first follower, as the env's agent does.

At ``policy_frequency > 0`` an env step spans several control periods. The controller is
still stepped at its own period: the action the policy returns is the first period's, and
the env asks the policy for each further period of that env step (the policy hands the env
a sub-step hook with every action). So the controller sees what it sees in ``ego run`` and
gives the same metrics at any ``policy_frequency``.

With the default normalised ``EgoState`` (relative time and station) the policy reads the
controller's observation from the env it drives (the same values, unnormalised); with
``normalize=False`` it rebuilds it from the vector.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ego.control import controller_spec
from ego.control.base import Observation
from ego.control.following import FollowingObservation, member_seed
from ego.models.longitudinal import SpacingPolicy
from ego.params import ConfigError, apply_overrides


class ControllerPolicy:
    """A controller as a policy of ``env`` (an :class:`ego.gym.EgoEnv`, possibly wrapped).

    ``params``: the controller's parameters (names as for ``--set``) when ``controller`` is a
    name. The controller is reset (with the run's seed) when the scenario resets its own: at
    every episode's start and when a task hands over to its controller (the curve's
    engagement); with a channel left to the env's controller, whenever an observation's time
    is 0. :meth:`reset` does it by hand.
    """

    def __init__(self, controller: Any, env, params: Mapping[str, Any] | None = None) -> None:
        self.env = env.unwrapped
        task = self.env.task
        if self.env.observation_type.type_name != "EgoState":
            raise ConfigError(
                f"a controller policy needs the EgoState observation (the env has "
                f"{self.env.observation_type.type_name})"
            )
        if isinstance(controller, str):
            spec = controller_spec(controller, task)
            built, _ = apply_overrides(spec.params(), params or {})
            controller = spec.build(built, self.env.scenario.config.dt)
        self.controller = controller
        names = self.env.observation_type.names
        # a car-following observation (its spacing policy among the fields) or a road one
        self.following = "headway" in names
        self._obs = FollowingObservation() if self.following else Observation()
        self._fields = [(i, n) for i, n in enumerate(names) if n not in ("standstill_gap", "headway")]
        self._policy = [names.index("standstill_gap"), names.index("headway")] if self.following else None
        self._t = names.index("t")
        self._to_action = self.env.action_type.from_native
        self._native = self.env.action_type.native
        self._direct = self.env.observation_type.normalize
        self._slot, self._resets, self._bridge = None, 0, None

    def reset(self, seed: int | None = None) -> None:
        """Reset the controller (the platoon's first follower's controller seeds as in a run)."""
        self.controller.reset(seed=member_seed(seed, 0) if self.following else seed)
        if not self.following:
            # controllers that preview the road read the lane off the observation
            self._obs.lane = getattr(getattr(self.env.scenario, "obs", None), "lane", None)

    def _follow_resets(self) -> None:
        """Reset the controller when the scenario reset its own: a new run (a new SUMO
        bridge), or a hand-over the agent's slot counted."""
        sc = self.env.scenario
        slot = sc.controller
        resets = getattr(slot, "resets", None)
        if resets is not None:
            if resets != self._resets or slot is not self._slot:  # a rebuilt env has a new slot
                self._slot, self._resets = slot, resets
                self.reset(slot.seed)
        elif sc.bridge is not self._bridge:
            self._bridge = sc.bridge
            self.reset(sc.seed)

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        self._follow_resets()
        if self._direct:
            o = self.env._view.obs
        else:
            values = np.asarray(observation, dtype=np.float64).tolist()
            o = self._obs
            for i, name in self._fields:
                setattr(o, name, values[i])
            if self._policy is not None:
                o.policy = SpacingPolicy(values[self._policy[0]], values[self._policy[1]])
        command, delta = self.controller.step(o)
        if self.env._every > 1:
            self.env._substep = self._substep
        return self._to_action(command, delta)

    def _substep(self):
        """The controller's command for one further control period of an env step (called by
        the env), as the env's action type passes it."""
        self._follow_resets()
        command, delta = self.controller.step(self.env._view.obs)
        return self._native(self._to_action(command, delta))
