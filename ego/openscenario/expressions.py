"""Parameter references and expressions of OpenSCENARIO XML attributes.

An attribute's value is a literal, a reference ``$name`` to a declared parameter (the whole
value), or (OpenSCENARIO 1.1) an expression ``${...}``: numbers, ``$name`` references,
``+ - * /``, unary minus, parentheses and the standard's functions (``sqrt(x)``, ``abs(x)``,
``pow(x, y)``, ``min``, ``max``... :data:`FUNCTIONS`), evaluated left to right with the usual
precedence (``* /`` before ``+ -``). Anything else in an expression is an error naming it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

_TOKEN = re.compile(r"\s*(?:(\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?)|\$([A-Za-z_][\w]*)|([A-Za-z_]\w*)|(.))")


def _sign(x: float) -> float:
    return float((x > 0) - (x < 0))


#: the functions of OpenSCENARIO 1.1+ expressions: name -> (arity, function)
FUNCTIONS = {
    "round": (1, lambda x: float(math.floor(x + 0.5))),
    "floor": (1, lambda x: float(math.floor(x))),
    "ceil": (1, lambda x: float(math.ceil(x))),
    "sqrt": (1, math.sqrt),
    "abs": (1, abs),
    "sign": (1, _sign),
    "sin": (1, math.sin),
    "cos": (1, math.cos),
    "tan": (1, math.tan),
    "asin": (1, math.asin),
    "acos": (1, math.acos),
    "atan": (1, math.atan),
    "pow": (2, math.pow),
    "min": (2, min),
    "max": (2, max),
}


class ExpressionError(ValueError):
    """A bad reference or expression; the message names what is wrong."""


def is_reference(text: str) -> bool:
    """True for ``$name`` and ``${...}`` values."""
    return text.startswith("$")


def resolve(text: str, values: Mapping[str, object]) -> object:
    """The value of an attribute ``text``: itself, a parameter's value (``$name``) or an
    expression's (``${...}``, a float)."""
    if not text.startswith("$"):
        return text
    if text.startswith("${"):
        if not text.endswith("}"):
            raise ExpressionError(f"unterminated expression {text!r} (expected ${{...}})")
        return evaluate(text[2:-1], values)
    name = text[1:]
    if name not in values:
        raise ExpressionError(f"parameter {text!r} is not declared" + _known(values))
    return values[name]


def _known(values: Mapping[str, object]) -> str:
    return f" (declared: {', '.join(values)})" if values else " (no ParameterDeclarations)"


def evaluate(expr: str, values: Mapping[str, object]) -> float:
    """The number ``expr`` (the inside of ``${...}``) evaluates to."""
    tokens: list[tuple[str, object]] = []
    pos = 0
    expr = expr.rstrip()
    while pos < len(expr):
        m = _TOKEN.match(expr, pos)
        if m is None:  # only trailing blanks are left
            break
        number, name, func, other = m.groups()
        pos = m.end()
        if number is not None:
            tokens.append(("num", float(number)))
        elif name is not None:
            if name not in values:
                raise ExpressionError(
                    f"parameter '${name}' in expression '${{{expr}}}' is not declared" + _known(values)
                )
            tokens.append(("num", _number(name, values[name], expr)))
        elif func is not None:
            if func not in FUNCTIONS:
                raise ExpressionError(
                    f"unknown function {func!r} in expression '${{{expr}}}' (functions: {', '.join(FUNCTIONS)})"
                )
            tokens.append(("fn", func))
        elif other in "+-*/(),":
            tokens.append((other, None))
        else:
            raise ExpressionError(
                f"unexpected {other!r} in expression '${{{expr}}}' (allowed: numbers, "
                "$parameters, + - * /, parentheses and functions)"
            )
    if not tokens:
        raise ExpressionError("empty expression '${}'")
    parser = _Parser(tokens, expr)
    value = parser.sum()
    if parser.i != len(tokens):
        raise ExpressionError(f"unexpected {tokens[parser.i][0]!r} in expression '${{{expr}}}'")
    if not math.isfinite(value):
        raise ExpressionError(f"expression '${{{expr}}}' is not finite")
    return value


def _number(name: str, value: object, expr: str) -> float:
    if isinstance(value, bool):
        raise ExpressionError(f"parameter '${name}' in expression '${{{expr}}}' is a boolean, not a number")
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ExpressionError(f"parameter '${name}' = {value!r} in expression '${{{expr}}}' is not a number") from None


#: parentheses and unary signs nested deeper than this are refused
MAX_NESTING = 100


class _Parser:
    """Recursive descent: sum := product (('+'|'-') product)*; product := unary (('*'|'/')
    unary)*; unary := '-' unary | '+' unary | atom; atom := number | '(' sum ')'."""

    def __init__(self, tokens: list[tuple[str, object]], expr: str) -> None:
        self.tokens, self.i, self.expr = tokens, 0, expr
        self.depth = 0

    def _deeper(self) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            short = self.expr if len(self.expr) <= 60 else self.expr[:57] + "..."
            raise ExpressionError(
                f"expression '${{{short}}}' is nested deeper than {MAX_NESTING} levels "
                "(parentheses and signs; the limit)"
            )

    def _peek(self) -> str | None:
        return self.tokens[self.i][0] if self.i < len(self.tokens) else None

    def sum(self) -> float:
        value = self.product()
        while self._peek() in ("+", "-"):
            op = self.tokens[self.i][0]
            self.i += 1
            rhs = self.product()
            value = value + rhs if op == "+" else value - rhs
        return value

    def product(self) -> float:
        value = self.unary()
        while self._peek() in ("*", "/"):
            op = self.tokens[self.i][0]
            self.i += 1
            rhs = self.unary()
            if op == "*":
                value *= rhs
            elif rhs == 0.0:
                raise ExpressionError(f"division by zero in expression '${{{self.expr}}}'")
            else:
                value /= rhs
        return value

    def unary(self) -> float:
        kind = self._peek()
        if kind in ("-", "+"):
            self.i += 1
            self._deeper()
            value = self.unary()
            self.depth -= 1
            return -value if kind == "-" else value
        return self.atom()

    def atom(self) -> float:
        kind = self._peek()
        if kind == "num":
            value = self.tokens[self.i][1]
            self.i += 1
            return value  # type: ignore[return-value]
        if kind == "fn":
            return self.call()
        if kind == "(":
            self.i += 1
            self._deeper()
            value = self.sum()
            self.depth -= 1
            if self._peek() != ")":
                raise ExpressionError(f"missing ')' in expression '${{{self.expr}}}'")
            self.i += 1
            return value
        what = "the end" if kind is None else repr(kind)
        raise ExpressionError(
            f"unexpected {what} in expression '${{{self.expr}}}' (expected a number, a $parameter or '(')"
        )

    def call(self) -> float:
        name = self.tokens[self.i][1]
        arity, fn = FUNCTIONS[name]  # type: ignore[index]
        self.i += 1
        if self._peek() != "(":
            raise ExpressionError(f"missing '(' after {name} in expression '${{{self.expr}}}'")
        self.i += 1
        args = [self.sum()]
        while self._peek() == ",":
            self.i += 1
            args.append(self.sum())
        if self._peek() != ")":
            raise ExpressionError(f"missing ')' in expression '${{{self.expr}}}'")
        self.i += 1
        if len(args) != arity:
            raise ExpressionError(
                f"{name} takes {arity} argument{'s' if arity > 1 else ''}, not {len(args)}, "
                f"in expression '${{{self.expr}}}'"
            )
        try:
            return float(fn(*args))
        except (ValueError, OverflowError):
            raise ExpressionError(
                f"{name}({', '.join(f'{a:g}' for a in args)}) is undefined in expression '${{{self.expr}}}'"
            ) from None
