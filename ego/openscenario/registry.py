"""The element registry: every OpenSCENARIO element ego reads, declared once.

Each element is declared with where it may appear (its parent elements) and what it may
contain; an action is one :class:`ActionKind` (its element, its own sub-elements, how it is
read, which domains of its actor it drives, whether it may act on the ego or in ``Init``, and
how it runs: start, step, stop) registered with :func:`register`, a condition one
:class:`ConditionKind` (read, evaluated) registered with :func:`register_condition`. From
these declarations:

* :func:`allowed` - the allow-list (element -> the children it may hold) that both
  ``ego run`` (:func:`ego.openscenario.loader.load`) and ``ego list`` check files against;
* :func:`action_of` and :data:`CONDITIONS` - the dispatch of the loader and of the storyboard
  from an element or a read action to its kind;
* :func:`table_rows` - the supported-subset table of docs/openscenario.md
  (``python -m ego.docs openscenario-table``), each row's notes written beside the element.

The structural elements (file, entities, storyboard, triggers, positions) are declared in
:mod:`ego.openscenario.structure`, the actions in :mod:`ego.openscenario.actions`, the
conditions in :mod:`ego.openscenario.conditions`; an element added from outside the package
registers the same way (docs/architecture.md, "Adding an OpenSCENARIO action").
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:
    from ego.openscenario.xmltree import Node

#: the runtime's ActionRun and Storyboard (ego.openscenario.runtime imports this module)
ActionRun = Any
Storyboard = Any

#: the sections of the subset table, in order
SECTIONS = ("file", "storyboard", "actions", "global", "conditions", "other")


@dataclass
class Element:
    """One element ego reads: where it may appear and what it may hold; ``note`` (with
    ``label``, ``also`` and ``section``) is its row of the subset table."""

    tag: str
    within: set[str] = field(default_factory=set)
    contains: set[str] = field(default_factory=set)
    like: str = ""  #: also holds whatever this other element holds (TargetPosition: Position)
    note: str = ""
    label: str = ""
    also: tuple[str, ...] = ()  #: the other elements its row documents
    section: str = "file"


@dataclass(frozen=True)
class Refused:
    """A row of the subset table for elements ego refuses (not in the allow-list)."""

    label: str
    tags: tuple[str, ...]
    note: str = ""
    section: str = "other"


ELEMENTS: dict[str, Element] = {}
REFUSED: list[Refused] = []
ACTIONS: dict[str, ActionKind] = {}  #: element tag -> its kind
_BY_MODEL: dict[type, ActionKind] = {}
_ALLOWED: dict[str, frozenset[str]] | None = None


def declare(
    tag: str,
    within: Iterable[str] = (),
    contains: Iterable[str] = (),
    *,
    like: str = "",
    note: str = "",
    label: str = "",
    also: tuple[str, ...] = (),
    section: str = "",
) -> Element:
    """Declare (or extend) the element ``tag``: it may appear in ``within`` and hold
    ``contains``; a second declaration of the same tag adds places and children."""
    global _ALLOWED
    el = ELEMENTS.setdefault(tag, Element(tag))
    el.within.update(within)
    el.contains.update(contains)
    el.like = like or el.like
    if note:
        el.note, el.label, el.also = note, label, also
    if section:
        el.section = section
    _ALLOWED = None
    return el


def refuse(label: str, tags: tuple[str, ...], note: str = "", section: str = "other") -> None:
    """Document elements ego refuses (a row of the subset table; they stay out of the allow-list)."""
    REFUSED.append(Refused(label, tags, note, section))


def allowed() -> dict[str, frozenset[str]]:
    """Every element ego reads -> the children it may hold (derived from the declarations)."""
    global _ALLOWED
    if _ALLOWED is None:
        kids: dict[str, set[str]] = {tag: set(el.contains) for tag, el in ELEMENTS.items()}
        for el in ELEMENTS.values():
            for parent in el.within:
                kids.setdefault(parent, set()).add(el.tag)
        for el in ELEMENTS.values():
            if el.like:
                kids[el.tag] |= kids.get(el.like, set())
        _ALLOWED = {tag: frozenset(c) for tag, c in kids.items() if tag in ELEMENTS}
    return _ALLOWED


class ActionKind:
    """One OpenSCENARIO action element: declared, read, and run.

    Subclass it, set the class attributes, implement :meth:`build` (and :meth:`start` /
    :meth:`step` for an action that moves its actor) and :func:`register` an instance."""

    tag: ClassVar[str]  #: the element's name
    within: ClassVar[tuple[str, ...]]  #: the elements it may appear in (LongitudinalAction...)
    contains: ClassVar[tuple[str, ...]] = ()  #: the elements it holds directly
    #: its own sub-elements -> what each holds (a tuple of tags, or the tag of an element
    #: whose children it shares, e.g. "Position")
    parts: ClassVar[Mapping[str, tuple[str, ...] | str]] = {}
    model: ClassVar[type | None] = None  #: the model class :meth:`build` returns (dispatch)
    domains: ClassVar[tuple[str, ...]] = ("long", "lat")  #: what of its actor it drives
    on_ego: ClassVar[bool] = False  #: allowed on the ego (it moves the ego's references)
    #: in Init: "no", "yes" (kept: the start), "runs" (started at t = 0 and left running, as
    #: the standard runs a non-instantaneous Init action: 8.5.1.2), or "ignored" (checked, not used)
    in_init: ClassVar[str] = "no"
    init_note: ClassVar[str] = ""  #: how the Init refusal names it ("" = not named)
    init_hint: ClassVar[str] = ""  #: what to write instead, where it is refused in Init
    is_global: ClassVar[bool] = False  #: a GlobalAction: done once, whoever the actors
    releases: ClassVar[bool] = False  #: its stop hands the actor back to SUMO's driver
    #: it places its actor: the one action that acts on an entity not in the simulation yet
    places: ClassVar[bool] = False
    #: its row of the subset table ("" = documented in another element's row)
    note: ClassVar[str] = ""
    label: ClassVar[str] = ""
    also: ClassVar[tuple[str, ...]] = ()
    section: ClassVar[str] = "actions"

    def build(self, b: Any, node: Node) -> Any:
        """The model of the action ``node`` (``b``: the loader's builder, its typed readers)."""
        raise NotImplementedError

    def domains_of(self, action: Any, ego: bool) -> tuple[str, ...]:
        """The domains this read action drives on its actor (``ego``: the actor is the ego)."""
        return self.domains

    def init_ok(self, action: Any) -> bool:
        """Whether this read action may stand in Init (when :attr:`in_init` is "yes" or "runs")."""
        return True

    def init_runs(self, action: Any) -> bool:
        """Whether this read action, in Init, keeps running from t = 0 (the storyboard starts
        it at its first step; a later action on the same domain overrides it)."""
        return self.in_init == "runs"

    def start(self, run: ActionRun, t: float) -> None:
        """Start on ``run.actor`` at ``t`` (default: done at once)."""
        run.finished = True

    def step(self, run: ActionRun, t: float) -> None:
        """Command ``run.actor`` for [t, t + step]."""

    def apply(self, board: Storyboard, action: Any) -> None:
        """A global action: what it does when its event starts."""


class ConditionKind:
    """One OpenSCENARIO condition element (in an EntityCondition or a ByValueCondition):
    declared, read into a :class:`~ego.openscenario.model.Condition`, evaluated every
    storyboard step. Subclass it and :func:`register_condition` an instance."""

    tag: ClassVar[str]
    within: ClassVar[tuple[str, ...]] = ("EntityCondition",)
    contains: ClassVar[tuple[str, ...]] = ()
    parts: ClassVar[Mapping[str, tuple[str, ...] | str]] = {}
    note: ClassVar[str] = ""
    label: ClassVar[str] = ""
    also: ClassVar[tuple[str, ...]] = ()
    section: ClassVar[str] = "conditions"

    def build(self, b: Any, node: Node, base: dict[str, Any]) -> Any:
        """The model (``base``: name, delay, edge, line and, for an entity condition, the
        triggering entities), read with the loader's builder ``b``."""
        raise NotImplementedError

    def holds(self, board: Storyboard, c: Any, e: Any, name: str) -> bool:
        """An entity condition: whether it holds for the triggering entity ``name`` (state ``e``)."""
        raise NotImplementedError

    def raw(self, board: Storyboard, c: Any, t: float) -> bool:
        """A value condition: whether it holds at storyboard time ``t``."""
        raise NotImplementedError


CONDITIONS: dict[str, ConditionKind] = {}  #: element tag -> its kind


def _declare_kind(kind: ActionKind | ConditionKind) -> None:
    declare(
        kind.tag, kind.within, kind.contains, note=kind.note, label=kind.label, also=kind.also, section=kind.section
    )
    for part, holds in kind.parts.items():
        if isinstance(holds, str):
            declare(part, like=holds)
        else:
            declare(part, contains=holds)


def register_condition(kind: ConditionKind) -> ConditionKind:
    """Register a condition kind: its element joins the allow-list, its tag the dispatch of
    the loader and of the storyboard, its note the subset table."""
    CONDITIONS[kind.tag] = kind
    _declare_kind(kind)
    return kind


def register(kind: ActionKind) -> ActionKind:
    """Register an action kind: its element and sub-elements join the allow-list, its model
    class the runtime dispatch, its note the subset table."""
    ACTIONS[kind.tag] = kind
    if kind.model is not None:
        _BY_MODEL.setdefault(kind.model, kind)
    _declare_kind(kind)
    return kind


def action_of(action: object) -> ActionKind:
    """The kind of a read action (by its model class)."""
    return _BY_MODEL[type(action)]


def init_kinds() -> str:
    """What Init takes, as the refusal names it: "A, B and C"."""
    names = [k.init_note for k in ACTIONS.values() if k.init_note]
    return ", ".join(names[:-1]) + (" and " if len(names) > 1 else "") + names[-1]


def table_rows() -> list[tuple[str, str, str, tuple[str, ...]]]:
    """The subset table's rows in section order: (label, supported, note, element tags)."""
    rows: list[tuple[str, str, str, tuple[str, ...], str]] = []
    for el in ELEMENTS.values():
        if el.note:
            rows.append((el.label or f"`{el.tag}`", "yes", el.note, (el.tag, *el.also), el.section))
    for r in REFUSED:
        rows.append((r.label, "no", r.note, r.tags, r.section))
    rows.sort(key=lambda r: SECTIONS.index(r[4]))
    return [r[:4] for r in rows]
