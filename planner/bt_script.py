"""BehaviorTree.CPP v4's scripting language: the code of ``Script``, ``ScriptCondition`` and
the ``_skipIf`` / ``_post`` ... attributes, parsed by a small tokenizer and a Pratt parser of
our own and evaluated over a blackboard given as a :class:`ScriptEnv`. User text never reaches
Python's ``eval``.

The language, as BT.CPP 4.10 defines it (its Pratt parser, since 4.9):

* statements separated by ``;``; a script returns the value of its last statement;
* assignment ``:=`` (creates the entry if absent), ``=`` (the entry must exist), ``+=``,
  ``-=``, ``*=``, ``/=``; the target is a blackboard key, ``@key`` for the root blackboard;
* ``+ - * /`` on numbers (``/`` always divides as reals: ``5 / 2`` is 2.5), ``+`` also joins
  two strings; unary ``-``; ``& | ^ ~`` on integral numbers; ``..`` joins strings and numbers;
* comparisons ``== != < <= > >=``, chained as a list (``a < b < c`` is ``a < b and b < c``);
  reals are equal within float epsilon; a string compared with a number is read as a number
  (``'true'``, ``'false'`` and enum names included), and is an error if it is not one;
* ``&&`` binds tighter than ``||`` (4.8 and earlier gave them one level), ``!`` negates; the
  words ``and``, ``or`` and ``not`` are not operators;
* ``cond ? a : b`` (``c ? a : b ? x : y`` is ``c ? a : (b ? x : y)``); parentheses;
  integers, reals (``3.14``, ``3e-2``), hex ``0x1F``, single-quoted strings without
  escapes, ``true`` and ``false``;
* enum names registered by the host read as integers, and win over a key of the same name;
* precedence, loosest first: assignment, ``?:``, ``||``, ``&&``, comparisons, ``| ^``,
  ``&``, ``+ - ..``, ``* /``, the prefixes; binary operators group left to right, so
  ``a + b & c`` is ``(a + b) & c`` and ``'a' .. 1 + 2`` is ``('a' .. 1) + 2``, an error.

Where Python lets us keep more than BT.CPP's doubles, values stay ``int`` through ``+ - *``
and the bitwise operators, become ``float`` through ``/``, and comparisons and logic give
``bool``. Overflow, division by zero and non-finite results are runtime errors.
"""

import math
from dataclasses import dataclass, field
from functools import lru_cache
from numbers import Integral, Real
from typing import Any, Protocol

from planner.bt_script_syntax import (
    INT64_MAX,
    INT64_MIN,
    MAX_DEPTH,
    MAX_SOURCE_CHARS,
    Assign,
    Chain,
    If,
    Literal,
    Name,
    Node,
    ScriptError,
    ScriptRuntimeError,
    Unary,
    parse,
    walk,
)

_FLT_EPSILON = 1.1920928955078125e-07


class ScriptEnv(Protocol):
    """The blackboard a script runs on. Keys are as written, ``@`` kept for root keys."""

    def read(self, key: str) -> Any: ...  # raises KeyError if absent

    def write(self, key: str, value: Any) -> None: ...

    def exists(self, key: str) -> bool: ...

    def enum(self, name: str) -> int | None: ...  # None: not an enum name


class DictEnv:
    """A :class:`ScriptEnv` over a plain dict, for tests and the validator's dry runs.

    Parameters
    ----------
    values : dict, optional
        Initial entries, key as written (``'@x'`` for a root key); copied.
    enums : dict, optional
        Enum name -> integer.
    """

    def __init__(
        self, values: dict[str, Any] | None = None, enums: dict[str, int] | None = None
    ) -> None:
        self.values: dict[str, Any] = dict(values or {})
        self.enums: dict[str, int] = dict(enums or {})

    def read(self, key: str) -> Any:
        return self.values[key]

    def write(self, key: str, value: Any) -> None:
        self.values[key] = value

    def exists(self, key: str) -> bool:
        return key in self.values

    def enum(self, name: str) -> int | None:
        return self.enums.get(name)


# ---------------------------------------------------------------------------------------------
# Values


def _is_number(value: Any) -> bool:
    return isinstance(value, Real)


def _as_number(value: Any) -> int | float:
    """A script number: bool and integral types become int, other reals float."""
    if isinstance(value, Integral):
        return int(value)
    return float(value)


def _text(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, Integral):
        return str(int(value))
    number = float(value)
    return str(int(number)) if number.is_integer() else repr(number)


def _kind(value: Any) -> str:
    if isinstance(value, str):
        return f"string {value!r}"
    if isinstance(value, bool):
        return f"boolean {_text(value)}"
    if _is_number(value):
        return f"number {_text(value)}"
    return f"a value of type {type(value).__name__}"


def truthy(value: Any) -> bool:
    """Whether a condition script's result counts as true, as BT.CPP casts it to bool: a
    number is true when non-zero; a string must read as a boolean (``'true'``, ``'false'``,
    ``'1'``, ``'0'``, any case).

    Raises
    ------
    ScriptRuntimeError
        For any other string, or a value that is neither number nor string.
    """
    if _is_number(value):
        return _as_number(value) != 0
    if isinstance(value, str):
        word = value.strip().lower()
        if word in ("true", "1"):
            return True
        if word in ("false", "0"):
            return False
    raise ScriptRuntimeError(
        "",
        1,
        f"a condition must give a number or a boolean, got {_kind(value)}",
    )


class _Run:
    """One evaluation: the source (for error columns) and the environment."""

    def __init__(self, source: str, env: ScriptEnv) -> None:
        self.source = source
        self.env = env

    def fail(self, column: int, reason: str) -> ScriptRuntimeError:
        return ScriptRuntimeError(self.source, column, reason)

    def checked(self, value: int | float, column: int, op: str) -> int | float:
        if isinstance(value, float) and not math.isfinite(value):
            raise self.fail(column, f"'{op}' gives {value}: numbers must stay finite")
        if isinstance(value, int) and not INT64_MIN <= value <= INT64_MAX:
            raise self.fail(column, f"'{op}' overflows a 64-bit integer")
        return value

    def to_number(self, value: Any, column: int, op: str) -> int | float:
        """A comparison operand read as a number: strings as BT.CPP reads them."""
        if _is_number(value):
            return _as_number(value)
        if isinstance(value, str):
            if value == "true":
                return 1
            if value == "false":
                return 0
            enum = self.env.enum(value)
            if enum is not None:
                return int(enum)
            try:
                number = float(value.strip())
            except ValueError:
                number = math.nan
            if math.isfinite(number):
                return int(number) if number.is_integer() and "." not in value else number
            raise self.fail(column, f"'{op}' cannot compare {_kind(value)} with a number")
        raise self.fail(column, f"'{op}' cannot compare {_kind(value)}")

    def read(self, node: Name) -> Any:
        if not node.key.startswith("@"):
            enum = self.env.enum(node.key)
            if enum is not None:
                return int(enum)
        try:
            value = self.env.read(node.key)
        except KeyError:
            raise self.fail(
                node.column, f"variable '{node.key}' not found on the blackboard"
            ) from None
        if value is None:
            raise self.fail(node.column, f"variable '{node.key}' is not initialised")
        return value

    def evaluate(self, node: Node) -> Any:
        if isinstance(node, Literal):
            return node.value
        if isinstance(node, Name):
            return self.read(node)
        if isinstance(node, Unary):
            return self.unary(node)
        if isinstance(node, Chain):
            if node.family == "compare":
                return self.compare(node)
            value = self.evaluate(node.first)
            for op, column, operand in node.rest:
                value = self.binary(op, value, self.evaluate(operand), column)
            return value
        if isinstance(node, If):
            condition = self.evaluate(node.condition)
            if isinstance(condition, str):
                chosen = condition != ""
            elif _is_number(condition):
                chosen = _as_number(condition) != 0
            else:
                raise self.fail(node.column, f"'?' cannot test {_kind(condition)}")
            return self.evaluate(node.then if chosen else node.otherwise)
        return self.assign(node)

    def unary(self, node: Unary) -> Any:
        value = self.evaluate(node.operand)
        if not _is_number(value):
            raise self.fail(node.column, f"unary '{node.op}' needs a number, got {_kind(value)}")
        number = _as_number(value)
        if node.op == "-":
            return self.checked(-number, node.column, "-")
        if node.op == "!":
            return number == 0
        return ~self.integer(number, node.column, "~")

    def integer(self, number: int | float, column: int, op: str) -> int:
        if isinstance(number, int):
            return number
        if number.is_integer() and INT64_MIN <= number <= INT64_MAX:
            return int(number)
        raise self.fail(column, f"'{op}' needs integers, got {_text(number)}")

    def binary(self, op: str, left: Any, right: Any, column: int) -> Any:
        if _is_number(left) and _is_number(right):
            a, b = _as_number(left), _as_number(right)
            if op == "&&":
                return a != 0 and b != 0
            if op == "||":
                return a != 0 or b != 0
            if op == "..":
                return _text(left) + _text(right)
            if op in ("&", "|", "^"):
                x, y = self.integer(a, column, op), self.integer(b, column, op)
                return x & y if op == "&" else x | y if op == "|" else x ^ y
            return self.arithmetic(op, a, b, column)
        if isinstance(left, str) and isinstance(right, str) and op in ("+", ".."):
            return left + right
        if op == ".." and all(isinstance(v, str) or _is_number(v) for v in (left, right)):
            return _text(left) + _text(right)
        raise self.fail(column, f"'{op}' is not defined for {_kind(left)} and {_kind(right)}")

    def arithmetic(self, op: str, a: int | float, b: int | float, column: int) -> int | float:
        if op == "+":
            result = a + b
        elif op == "-":
            result = a - b
        elif op == "*":
            result = a * b
        else:
            if b == 0:
                raise self.fail(column, "division by zero")
            result = a / b
        return self.checked(result, column, op)

    def compare(self, node: Chain) -> bool:
        left = self.evaluate(node.first)
        for op, column, operand in node.rest:
            right = self.evaluate(operand)
            if isinstance(left, str) and isinstance(right, str):
                holds = _holds(op, left, right, exact=True)
            elif (
                isinstance(left, str)
                or isinstance(right, str)
                or (_is_number(left) and _is_number(right))
            ):
                a, b = self.to_number(left, column, op), self.to_number(right, column, op)
                exact = isinstance(a, int) and isinstance(b, int)
                holds = _holds(op, a, b, exact=exact)
            else:
                raise self.fail(column, f"'{op}' cannot compare {_kind(left)} with {_kind(right)}")
            if not holds:
                return False
            left = right
        return True

    def assign(self, node: Assign) -> Any:
        env = self.env
        if not env.exists(node.key):
            if node.op != ":=":
                raise self.fail(
                    node.column,
                    f"the blackboard entry '{node.key}' does not exist yet: "
                    f"use ':=' to create it, not '{node.op}'",
                )
            value = self.evaluate(node.value)
            env.write(node.key, value)
            return value
        value = self.evaluate(node.value)
        old = env.read(node.key)
        if node.op in (":=", "="):
            new = self.converted(node, old, value)
        else:
            new = self.compound(node, old, value)
        env.write(node.key, new)
        return new

    def converted(self, node: Assign, old: Any, value: Any) -> Any:
        """BT.CPP keeps an entry's type once it holds a value: a string may go into a number
        entry only if it reads as a number, a number never into a string entry."""
        if old is None:
            return value
        if _is_number(old) and isinstance(value, str):
            try:
                return self.to_number(value, node.column, node.op)
            except ScriptRuntimeError:
                raise self.fail(
                    node.column,
                    f"'{node.key}' holds a number; cannot assign {_kind(value)} to it",
                ) from None
        if isinstance(old, str) and not isinstance(value, str):
            raise self.fail(
                node.column,
                f"'{node.key}' holds a string; cannot assign {_kind(value)} to it",
            )
        return value

    def compound(self, node: Assign, old: Any, value: Any) -> Any:
        op = node.op[0]
        if old is None:
            raise self.fail(node.column, f"'{node.key}' is not initialised, cannot use '{node.op}'")
        if _is_number(old) and _is_number(value):
            return self.arithmetic(op, _as_number(old), _as_number(value), node.column)
        if isinstance(old, str) and isinstance(value, str) and op == "+":
            return old + value
        raise self.fail(
            node.column, f"'{node.op}' is not defined for {_kind(old)} and {_kind(value)}"
        )


def _holds(op: str, a: Any, b: Any, *, exact: bool) -> bool:
    if op in ("==", "!="):
        same = a == b if exact else abs(float(a) - float(b)) <= _FLT_EPSILON
        return same if op == "==" else not same
    if op == "<":
        return bool(a < b)
    if op == "<=":
        return bool(a <= b)
    if op == ">":
        return bool(a > b)
    return bool(a >= b)


@dataclass(frozen=True)
class Script:
    """A parsed script. Build it with :func:`parse_script` (or ``Script(source)``, which
    parses too and raises :class:`ScriptError`)."""

    source: str
    _statements: tuple[Node, ...] = field(default=(), repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self._statements:
            object.__setattr__(self, "_statements", parse(self.source))

    def evaluate(self, env: ScriptEnv) -> Any:
        """Run every statement on ``env``; return the last statement's value.

        Raises
        ------
        ScriptRuntimeError
            An undefined key, ``=`` on a missing entry, bad operand types, an overflow.
        """
        run = _Run(self.source, env)
        value: Any = None
        for statement in self._statements:
            value = run.evaluate(statement)
        return value

    def keys_read(self) -> frozenset[str]:
        """Keys the script may read: every name used as a value (enum names among them; the
        host knows which they are) and the targets of compound assignments."""
        found: set[str] = set()
        for statement in self._statements:
            for node in walk(statement):
                if isinstance(node, Name):
                    found.add(node.key)
                elif isinstance(node, Assign) and node.op not in (":=", "="):
                    found.add(node.key)
        return frozenset(found)

    def keys_written(self) -> frozenset[str]:
        """Keys the script may write: the targets of its assignments."""
        return frozenset(
            node.key
            for statement in self._statements
            for node in walk(statement)
            if isinstance(node, Assign)
        )


@lru_cache(maxsize=1024)
def _cached(source: str) -> Script:
    return Script(source, parse(source))


def parse_script(source: str) -> Script:
    """Parse ``source`` into a :class:`Script` (pure, cached on the text).

    Raises
    ------
    ScriptError
        With the 1-based column and the reason, when the script does not parse, is longer
        than :data:`MAX_SOURCE_CHARS` or nests deeper than :data:`MAX_DEPTH`.
    """
    if not isinstance(source, str):
        raise ScriptError(str(source), 1, f"a script must be text, got {type(source).__name__}")
    return _cached(source)


__all__: list[str] = [
    "MAX_DEPTH",
    "MAX_SOURCE_CHARS",
    "DictEnv",
    "Script",
    "ScriptEnv",
    "ScriptError",
    "ScriptRuntimeError",
    "parse_script",
    "truthy",
]
