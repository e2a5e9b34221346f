"""The TimeOfDayCondition: the scenario's time of day (the Init's TimeOfDay, moving on with the
simulation time when it is animated) compared with a date and time."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from ego.openscenario import model as M
from ego.openscenario.registry import ConditionKind, Storyboard, register_condition
from ego.openscenario.runtime import compare
from ego.openscenario.xmltree import DOCS, Node


def parse_time(b: Any, node: Node, name: str = "dateTime") -> float:
    """An xsd:dateTime attribute as seconds since 1970 (UTC; a time without a zone is UTC)."""
    text = str(b.raw(node, name)).strip()
    try:
        t = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise b.error(
            node, f"bad value for {name} in <{node.tag}>: {text!r} (expected a date and time, 2025-06-13T12:00:00)"
        ) from None
    if t.tzinfo is None:
        t = t.replace(tzinfo=UTC)
    return t.timestamp()


def _times_of_day(root: Node, under: str) -> list[Node]:
    """The TimeOfDay elements of the EnvironmentActions below the storyboard's ``under`` part."""
    sb = root.child("Storyboard")
    out: list[Node] = []
    stack = [c for c in (sb.children if sb is not None else ()) if c.tag == under]
    while stack:
        n = stack.pop()
        if n.tag == "TimeOfDay":
            out.append(n)
        stack.extend(n.children)
    return out


class TimeOfDay(ConditionKind):
    tag, within = "TimeOfDayCondition", ("ByValueCondition",)
    note = (
        "the scenario's time of day, the `Init`'s `TimeOfDay` (an inline `EnvironmentAction`) at the start, moving "
        "on with the simulation time when `animation` is true, compared with `dateTime` by `rule` (a time without a "
        "zone is UTC); a file without an `Init` `TimeOfDay`, or whose storyboard changes it, is refused at the "
        "condition (`test_xosc_timeofday.py`)"
    )

    def build(self, b: Any, c: Node, base: dict[str, Any]) -> M.Condition:
        rule, value = b.enum(c, "rule", M.RULES), parse_time(b, c)
        root = b.scenario_tree()  # a maneuver catalog's condition: the scenario's Init
        init = _times_of_day(root, "Init")
        if not init:
            raise b.error(
                c,
                f"a <TimeOfDayCondition> needs the time of day the scenario starts at: an inline <TimeOfDay> in an "
                f"<Init> EnvironmentAction (see {DOCS})",
            )
        changed = _times_of_day(root, "Story")
        if changed:
            raise b.error(
                c,
                f"a <TimeOfDayCondition> where the storyboard changes the time of day (line {changed[0].line}) is "
                f"not supported by ego (see {DOCS})",
            )
        start = parse_time(b, init[0])
        animated = b.bool_(init[0], "animation")
        # the start's offset from the condition's time (s): small numbers keep the step's precision
        return M.Condition(kind=c.tag, rule=rule, value=(start - value, animated), **base)

    def raw(self, board: Storyboard, c: M.Condition, t: float) -> bool:
        offset, animated = c.value  # type: ignore[misc]
        return compare(c.rule, offset + (t if animated else 0.0), 0.0)


register_condition(TimeOfDay())
