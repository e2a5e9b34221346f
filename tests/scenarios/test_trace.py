"""Named traces: rows written by name, a wrong row rejected."""

import numpy as np
import pytest

from ego.results.trace import Column, Trace, TraceError

COLUMNS = (Column("t", "s", "time"), Column("gap", "m", "gap"), Column("speed", "m/s", "speed"))


def test_a_row_is_stored_in_declared_order_whatever_the_call_order():
    trace = Trace(COLUMNS, ("k_p",))
    trace.append({"k_p": 2.0}, speed=20.0, t=0.5, gap=12.0)
    assert trace.names == ("t", "gap", "speed", "k_p")
    assert np.array_equal(trace.array(), [[0.5, 12.0, 20.0, 2.0]])
    assert trace.units() == {"t": "s", "gap": "m", "speed": "m/s", "k_p": ""}


@pytest.mark.parametrize(
    "values, message",
    [
        (dict(t=0.0, gap=1.0), "missing speed"),
        (dict(t=0.0, gap=1.0, speed=2.0, sped=3.0), "unknown sped"),
        (dict(t=0.0, speed=2.0, gapp=1.0), "missing gap; unknown gapp"),
    ],
    ids=["missing", "unknown", "misspelt"],
)
def test_a_wrong_row_is_rejected_and_nothing_is_stored(values, message):
    trace = Trace(COLUMNS)
    with pytest.raises(TraceError, match=message):
        trace.append(None, **values)
    assert len(trace) == 0


def test_controller_signals_are_checked_by_name():
    trace = Trace(COLUMNS, ("a", "b"))
    with pytest.raises(TraceError, match="signals"):
        trace.append({"b": 1.0, "a": 2.0}, t=0.0, gap=1.0, speed=2.0)
    with pytest.raises(TraceError, match="signals"):
        trace.append(None, t=0.0, gap=1.0, speed=2.0)


def test_declarations_are_checked():
    with pytest.raises(TraceError, match="twice"):
        Trace(COLUMNS + (Column("gap", "m"),))
    with pytest.raises(TraceError, match="identifiers"):
        Trace((Column("a-b", "m"),))
    with pytest.raises(TraceError, match="clash"):
        Trace(COLUMNS, ("gap",))


def test_a_bound_writer_checks_its_names_once_and_each_row_length():
    trace = Trace(COLUMNS, ("k",))
    write = trace.bind(("speed", "t", "gap"))
    write({"k": 1.0}, (20.0, 0.1, 5.0))
    assert np.array_equal(trace.array(), [[0.1, 5.0, 20.0, 1.0]])
    with pytest.raises(TraceError, match="values"):
        write({"k": 1.0}, (20.0, 0.1))
    with pytest.raises(TraceError, match="missing gap"):
        trace.bind(("speed", "t"))
