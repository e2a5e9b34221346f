"""Robustness of a parsed STL formula (:mod:`ego.requirements`' trees) over sampled signals,
in numpy: rtamt's discrete-time offline semantics, node by node, without its Python loops
over samples (``tests/test_requirements.py`` checks every sample against rtamt's own).

A tree is a tuple whose first item names the node:

* formulas: ``("cmp", op, left, right)``, ``("bool", name)``, ``("const", True)``,
  ``("not", f)``, ``("and", (f, ...))``, ``("or", (f, ...))``, ``("implies", f, g)``,
  ``("group", f)``, ``("temporal", "always"|"eventually"|"historically"|"once", bounds, f)``,
  ``("until", bounds, f, g)``; ``bounds`` is ``(lo, hi)`` in seconds or None (unbounded);
* arithmetic: ``("num", text)``, ``("sig", name)``, ``("bin", op, a, b)``, ``("abs", a)``,
  ``("paren", a)``.

The semantics, for ``n`` samples ``step`` s apart (an interval bound at the nearest sample):
a comparison's robustness is ``left - right`` (``>=``, ``>``), ``right - left`` (``<=``,
``<``), ``-|left - right|`` (``==``), ``|left - right|`` (``!=``); ``not`` negates, ``and``
and ``or`` are min and max, ``a implies b`` is ``max(-a, b)``; ``always[a:b] f`` at sample k
is the min of f over samples k+a..k+b that exist (+inf when none does), ``eventually`` the
max (-inf when none), ``historically`` and ``once`` the same over k-b..k-a; unbounded, to the
trace's end (or from its start); ``f until[a:b] g`` at k is the max over m in k+a..k+b
(within the trace) of min(g at m, f at every sample from k to m-1).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

INF = float("inf")


def render(node: tuple) -> str:
    """The formula as rtamt's STL text (its interval bounds in seconds)."""
    kind = node[0]
    if kind == "num":
        return node[1]
    if kind == "sig":
        return node[1]
    if kind == "bin":
        return f"{render(node[2])} {node[1]} {render(node[3])}"
    if kind in ("paren", "group"):
        return f"({render(node[1])})"
    if kind == "abs":
        return f"abs({render(node[1])})"
    if kind == "cmp":
        return f"({render(node[2])} {node[1]} {render(node[3])})"
    if kind == "bool":
        return f"({node[1]} > 0)"
    if kind == "const":
        return "(1 > 0)" if node[1] else "(0 > 1)"
    if kind == "not":
        return f"not ({render(node[1])})"
    if kind in ("and", "or"):
        return f" {kind} ".join(f"({render(p)})" for p in node[1])
    if kind == "implies":
        return f"({render(node[1])}) implies ({render(node[2])})"
    if kind == "temporal":
        return f"{node[1]}{_bounds_text(node[2])} ({render(node[3])})"
    if kind == "until":
        return f"({render(node[2])}) until{_bounds_text(node[1])} ({render(node[3])})"
    raise ValueError(f"unknown node {kind!r}")


def _bounds_text(bounds) -> str:
    return "" if bounds is None else f"[{bounds[0]!r}:{bounds[1]!r}]"


def robustness(node: tuple, signals: Mapping[str, np.ndarray], n: int, step: float) -> np.ndarray:
    """The robustness signal of formula ``node`` at each of ``n`` samples ``step`` s apart,
    ``signals`` the named signals' values there (floats; booleans +1/-1). ZeroDivisionError
    where a divisor is 0 at some sample (rtamt's too: no number)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.broadcast_to(_formula(node, signals, n, step), (n,)).astype(float, copy=False)


def _samples(seconds: float, step: float) -> int:
    return round(seconds / step)


def _formula(node: tuple, sig: Mapping[str, np.ndarray], n: int, step: float) -> np.ndarray:
    kind = node[0]
    if kind == "cmp":
        left = _arith(node[2], sig)
        right = _arith(node[3], sig)
        op = node[1]
        if op == "==":
            out = -np.abs(left - right)
        elif op == "!=":
            out = np.abs(left - right)
        elif op in ("<=", "<"):
            out = right - left
        else:
            out = left - right
        return np.broadcast_to(np.asarray(out, dtype=float), (n,))
    if kind == "bool":
        return np.asarray(sig[node[1]], dtype=float) - 0.0
    if kind == "const":
        return np.full(n, 1.0 if node[1] else -1.0)
    if kind == "group":
        return _formula(node[1], sig, n, step)
    if kind == "not":
        return -_formula(node[1], sig, n, step)
    if kind in ("and", "or"):
        fn = np.minimum if kind == "and" else np.maximum
        out = _formula(node[1][0], sig, n, step)
        for part in node[1][1:]:
            out = fn(out, _formula(part, sig, n, step))
        return out
    if kind == "implies":
        return np.maximum(-_formula(node[1], sig, n, step), _formula(node[2], sig, n, step))
    if kind == "temporal":
        return _temporal(node[1], node[2], _formula(node[3], sig, n, step), step)
    if kind == "until":
        left = _formula(node[2], sig, n, step)
        right = _formula(node[3], sig, n, step)
        return _until(left, right, node[1], step)
    raise ValueError(f"unknown formula node {kind!r}")


def _arith(node: tuple, sig: Mapping[str, np.ndarray]):
    kind = node[0]
    if kind == "num":
        return float(node[1])
    if kind == "sig":
        return sig[node[1]]
    if kind == "paren":
        return _arith(node[1], sig)
    if kind == "abs":
        return np.abs(_arith(node[1], sig))
    a, b = _arith(node[2], sig), _arith(node[3], sig)
    op = node[1]
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if np.any(np.asarray(b) == 0.0):
        raise ZeroDivisionError("float division by zero")
    return a / b


def _temporal(op: str, bounds, x: np.ndarray, step: float) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    low = op in ("always", "historically")  # a min; else a max
    future = op in ("always", "eventually")
    if bounds is None:
        acc = np.minimum.accumulate if low else np.maximum.accumulate
        return acc(x[::-1])[::-1] if future else acc(x)
    a, b = _samples(bounds[0], step), _samples(bounds[1], step)
    if future:
        return _window(x, a, b, low)
    return _window(x[::-1], a, b, low)[::-1]


def _window(x: np.ndarray, a: int, b: int, low: bool) -> np.ndarray:
    """At each sample k, the min (``low``) or max of x over samples k+a..k+b that exist;
    +inf (min) or -inf (max) where none does."""
    n = len(x)
    fill = INF if low else -INF
    out = np.full(n, fill)
    if a >= n:
        return out
    b = min(b, n - 1)
    out[: n - a] = sliding(x[a:], b - a + 1, low)
    return out


def sliding(y: np.ndarray, w: int, low: bool) -> np.ndarray:
    """At each i, the min (``low``) or max of y[i : i + w], the samples past the end left
    out: van Herk and Gil-Werman's two passes over blocks of w, in numpy (O(n) whatever w;
    scipy.ndimage's filters do the same but cost 0.4 s CPU to import in every process)."""
    n = len(y)
    if w <= 1:
        return np.array(y, dtype=float)
    fill = INF if low else -INF
    acc = np.minimum.accumulate if low else np.maximum.accumulate
    m = -(-(n + w - 1) // w) * w  # whole blocks of w, room for the last window
    z = np.full(m, fill)
    z[:n] = y
    blocks = z.reshape(-1, w)
    ahead = acc(blocks, axis=1).ravel()  # from each block's start up to the sample
    behind = acc(blocks[:, ::-1], axis=1)[:, ::-1].ravel()  # from the sample to its block's end
    op = np.minimum if low else np.maximum
    return op(behind[:n], ahead[w - 1 : w - 1 + n])


def _until(left: np.ndarray, right: np.ndarray, bounds, step: float) -> np.ndarray:
    left = np.asarray(left, dtype=float)
    right = np.asarray(right, dtype=float)
    n = len(left)
    if bounds is None:
        out = np.empty(n)
        nxt = -INF
        for i in range(n - 1, -1, -1):  # rtamt's recursion: max(right, min(left, next))
            nxt = max(min(float(left[i]), nxt), float(right[i]))
            out[i] = nxt
        return out
    a, b = _samples(bounds[0], step), min(_samples(bounds[1], step), n - 1)
    out = np.full(n, -INF)
    held = np.full(n, INF)  # min of left over k..k+d-1
    for d in range(0, b + 1):
        if d >= a:
            reach = np.full(n, -INF)
            reach[: n - d] = np.minimum(right[d:], held[: n - d])
            out = np.maximum(out, reach)
        if d < n:
            held[: n - d] = np.minimum(held[: n - d], left[d:])
    return out
