"""BehaviorTree.CPP v4's scripting language: the code of ``Script``, ``ScriptCondition`` and
the ``_skipIf`` / ``_post`` ... attributes, parsed by a small tokenizer and a Pratt parser of
our own and evaluated over a blackboard given as a :class:`ScriptEnv`. User text never reaches
Python's ``eval``.

The language, as BT.CPP 4.x defines it:

* statements separated by ``;``; a script returns the value of its last statement;
* assignment ``:=`` (creates the entry if absent), ``=`` (the entry must exist), ``+=``,
  ``-=``, ``*=``, ``/=``; the target is a blackboard key, ``@key`` for the root blackboard;
* ``+ - * /`` on numbers (``/`` always divides as reals: ``5 / 2`` is 2.5), ``+`` also joins
  two strings; unary ``-``; ``& | ^ ~`` on integral numbers; ``..`` joins strings and numbers;
* comparisons ``== != < <= > >=``, chained as a list (``a < b < c`` is ``a < b and b < c``);
  reals are equal within float epsilon; a string compared with a number is read as a number
  (``'true'``, ``'false'`` and enum names included), and is an error if it is not one;
* ``&&`` and ``||`` share one precedence and group left to right, ``!`` negates; the words
  ``and``, ``or`` and ``not`` are not operators;
* ``cond ? a : b``; parentheses; integers, reals (``3.14``, ``3e-2``), hex ``0x1F``,
  single-quoted strings without escapes, ``true`` and ``false``;
* enum names registered by the host read as integers, and win over a key of the same name;
* arithmetic and bitwise operators do not mix without parentheses, nor do ``..`` and
  comparisons (``a + b & c`` is refused, ``(a + b) & c`` is not), as in BT.CPP.

Where Python lets us keep more than BT.CPP's doubles, values stay ``int`` through ``+ - *``
and the bitwise operators, become ``float`` through ``/``, and comparisons and logic give
``bool``. Overflow, division by zero and non-finite results are runtime errors.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import lru_cache
from numbers import Integral, Real
from typing import Any, Protocol

MAX_SOURCE_CHARS = 10_000
MAX_DEPTH = 100
_FLT_EPSILON = 1.1920928955078125e-07
_INT64_MIN = -(2**63)
_INT64_MAX = 2**63 - 1


class ScriptError(ValueError):
    """A script that does not parse.

    Attributes
    ----------
    source : str
        The script as given.
    column : int
        1-based column in ``source`` where the problem is.
    reason : str
        What is wrong and what was expected.
    """

    def __init__(self, source: str, column: int, reason: str) -> None:
        super().__init__(f"column {column}: {reason}")
        self.source = source
        self.column = column
        self.reason = reason

    def __reduce__(self) -> tuple[Any, tuple[str, int, str]]:
        # picklable for worker processes: the default would call __init__(message)
        return (type(self), (self.source, self.column, self.reason))


class ScriptRuntimeError(RuntimeError):
    """A script that parsed but cannot run on these values: an undefined key, ``=`` on a
    missing entry, operands of the wrong type, an overflow. Same attributes as
    :class:`ScriptError`; ``column`` points at the operator or the key."""

    def __init__(self, source: str, column: int, reason: str) -> None:
        super().__init__(f"column {column}: {reason}")
        self.source = source
        self.column = column
        self.reason = reason

    def __reduce__(self) -> tuple[Any, tuple[str, int, str]]:
        # picklable for worker processes: the default would call __init__(message)
        return (type(self), (self.source, self.column, self.reason))


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
# Tokens

_OPERATORS = (
    ":=",
    "+=",
    "-=",
    "*=",
    "/=",
    "==",
    "!=",
    "<=",
    ">=",
    "&&",
    "||",
    "..",
    "=",
    "<",
    ">",
    "+",
    "-",
    "*",
    "/",
    "&",
    "|",
    "^",
    "~",
    "!",
    "?",
    ":",
    "(",
    ")",
    ";",
)


@dataclass(frozen=True)
class _Token:
    kind: str  # "num", "str", "name", "op", "end"
    text: str
    column: int  # 1-based
    value: Any = None


def _is_name_start(ch: str) -> bool:
    return ch == "_" or (ch.isalpha() and ch.isascii())


def _is_name_char(ch: str) -> bool:
    return ch == "_" or (ch.isalnum() and ch.isascii())


def _tokenize(source: str) -> list[_Token]:
    tokens: list[_Token] = []
    i, n = 0, len(source)
    while i < n:
        ch = source[i]
        col = i + 1
        if ch in " \t\r\n":
            i += 1
        elif ch == "'":
            end = source.find("'", i + 1)
            if end < 0:
                raise ScriptError(source, col, "unterminated string: no closing '")
            tokens.append(_Token("str", source[i : end + 1], col, source[i + 1 : end]))
            i = end + 1
        elif ch.isdigit() and ch.isascii():
            i = _number(source, i, tokens)
        elif ch == "@" or _is_name_start(ch):
            j = i + 1
            if ch == "@" and not (j < n and _is_name_start(source[j])):
                raise ScriptError(source, col, "expected a key name after '@'")
            while j < n and _is_name_char(source[j]):
                j += 1
            text = source[i:j]
            if text in ("true", "false"):
                tokens.append(_Token("num", text, col, text == "true"))
            else:
                tokens.append(_Token("name", text, col))
            i = j
        else:
            for op in _OPERATORS:
                if source.startswith(op, i):
                    tokens.append(_Token("op", op, col))
                    i += len(op)
                    break
            else:
                raise ScriptError(source, col, f"unexpected character {ch!r}")
    tokens.append(_Token("end", "", n + 1))
    return tokens


def _number(source: str, i: int, tokens: list[_Token]) -> int:
    """Read the number at ``source[i]`` into ``tokens``; return the index after it."""
    n, col = len(source), i + 1
    j = i
    value: int | float
    if source.startswith(("0x", "0X"), i):
        j = i + 2
        while j < n and source[j] in "0123456789abcdefABCDEF":
            j += 1
        if j == i + 2:
            raise ScriptError(source, col, "expected hex digits after '0x'")
        value = int(source[i + 2 : j], 16)
    else:
        while j < n and source[j].isdigit() and source[j].isascii():
            j += 1
        real = False
        if j < n and source[j] == "." and not source.startswith("..", j):
            k = j + 1
            while k < n and source[k].isdigit() and source[k].isascii():
                k += 1
            if k == j + 1:
                raise ScriptError(source, j + 2, "expected digits after the decimal point")
            j, real = k, True
        if j < n and source[j] in "eE":
            k = j + 1
            if k < n and source[k] in "+-":
                k += 1
            start = k
            while k < n and source[k].isdigit() and source[k].isascii():
                k += 1
            if k == start:
                raise ScriptError(source, k + 1, "expected digits in the exponent")
            j, real = k, True
        text = source[i:j]
        value = float(text) if real else int(text)
    dot = source.startswith(".", j) and not source.startswith("..", j)
    if j < n and (_is_name_char(source[j]) or dot):
        raise ScriptError(source, j + 1, f"unexpected {source[j]!r} after the number {source[i:j]}")
    if isinstance(value, float) and not math.isfinite(value):
        raise ScriptError(source, col, f"number {source[i:j]} is out of range")
    if isinstance(value, int) and not _INT64_MIN <= value <= _INT64_MAX:
        raise ScriptError(source, col, f"integer {source[i:j]} does not fit in 64 bits")
    tokens.append(_Token("num", source[i:j], col, value))
    return j


# ---------------------------------------------------------------------------------------------
# Syntax tree. Binary chains are flat lists so that a long ``1+1+...+1`` never recurses deeply.


@dataclass(frozen=True)
class _Literal:
    value: Any
    column: int


@dataclass(frozen=True)
class _Name:
    key: str
    column: int


@dataclass(frozen=True)
class _Unary:
    op: str
    operand: _Node
    column: int


@dataclass(frozen=True)
class _Chain:
    """``first op1 x1 op2 x2 ...``, folded left (or, for comparisons, as a list)."""

    family: str  # "math", "bit", "concat", "compare", "logic"
    first: _Node
    rest: tuple[tuple[str, int, _Node], ...]  # (operator, column, operand)


@dataclass(frozen=True)
class _If:
    condition: _Node
    then: _Node
    otherwise: _Node
    column: int


@dataclass(frozen=True)
class _Assign:
    op: str
    key: str
    value: _Node
    column: int


_Node = _Literal | _Name | _Unary | _Chain | _If | _Assign

_ASSIGN_OPS = (":=", "=", "+=", "-=", "*=", "/=")
#: operator -> (family, left binding power)
_BINARY: dict[str, tuple[str, int]] = {
    "||": ("logic", 3),
    "&&": ("logic", 3),
    "==": ("compare", 4),
    "!=": ("compare", 4),
    "<": ("compare", 4),
    "<=": ("compare", 4),
    ">": ("compare", 4),
    ">=": ("compare", 4),
    "..": ("concat", 4),
    "+": ("math", 5),
    "-": ("math", 5),
    "|": ("bit", 5),
    "^": ("bit", 5),
    "*": ("math", 6),
    "/": ("math", 6),
    "&": ("bit", 6),
}
#: families that BT.CPP keeps apart unless parenthesised
_CLASH = {
    frozenset(("math", "bit")),
    frozenset(("concat", "compare")),
    frozenset(("concat", "bit")),
}
_PREFIX_BP = 7


class _Parser:
    def __init__(self, source: str) -> None:
        self.source = source
        self.tokens = _tokenize(source)
        self.pos = 0
        self.depth = 0

    def peek(self) -> _Token:
        return self.tokens[self.pos]

    def take(self) -> _Token:
        token = self.tokens[self.pos]
        self.pos += 1
        return token

    def fail(self, token: _Token, reason: str) -> ScriptError:
        return ScriptError(self.source, token.column, reason)

    def describe(self, token: _Token) -> str:
        return "the end of the script" if token.kind == "end" else repr(token.text)

    def statements(self) -> tuple[_Node, ...]:
        found: list[_Node] = []
        while True:
            while self.peek().text == ";" and self.peek().kind == "op":
                self.take()
            if self.peek().kind == "end":
                break
            found.append(self.expression(0)[0])
            token = self.peek()
            if token.kind == "end":
                break
            if not (token.kind == "op" and token.text == ";"):
                raise self.fail(token, f"expected an operator or ';', got {self.describe(token)}")
        if not found:
            raise ScriptError(self.source, 1, "empty script: expected at least one statement")
        return tuple(found)

    def nest(self, token: _Token) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.fail(token, f"nesting deeper than {MAX_DEPTH} levels")

    def expression(self, min_bp: int) -> tuple[_Node, str | None]:
        """Pratt loop; returns the node and the family of its top operator (None for an atom,
        a parenthesised expression or a unary operator)."""
        left, family = self.prefix()
        while True:
            token = self.peek()
            if token.kind != "op":
                return left, family
            op = token.text
            if op in _ASSIGN_OPS:
                if min_bp > 1:
                    return left, family
                if not isinstance(left, _Name) or family is not None:
                    raise self.fail(token, f"the left of '{op}' must be a blackboard key")
                self.take()
                self.nest(token)
                value, _ = self.expression(2)
                self.depth -= 1
                left, family = _Assign(op, left.key, value, token.column), "assign"
                if self.peek().kind == "op" and self.peek().text in _ASSIGN_OPS:
                    raise self.fail(self.peek(), "chained assignment needs parentheses")
                continue
            if op == "?":
                if min_bp > 2:
                    return left, family
                if family == "if":
                    raise self.fail(token, "a nested '?' needs parentheses")
                self.take()
                self.nest(token)
                then, _ = self.expression(0)
                colon = self.take()
                if not (colon.kind == "op" and colon.text == ":"):
                    raise self.fail(colon, f"expected ':' of '?', got {self.describe(colon)}")
                otherwise, _ = self.expression(3)
                self.depth -= 1
                left, family = _If(left, then, otherwise, token.column), "if"
                continue
            if op not in _BINARY:
                return left, family
            op_family, bp = _BINARY[op]
            if bp < min_bp:
                return left, family
            if family in ("assign", "if"):
                raise self.fail(token, f"'{op}' after '?:' or an assignment needs parentheses")
            if family is not None and frozenset((family, op_family)) in _CLASH:
                raise self.fail(
                    token, f"'{op}' cannot mix with {family} operators: add parentheses"
                )
            self.take()
            right, right_family = self.expression(bp + 1)
            if right_family is not None and frozenset((right_family, op_family)) in _CLASH:
                raise self.fail(
                    token, f"'{op}' cannot mix with {right_family} operators: add parentheses"
                )
            if isinstance(left, _Chain) and family == op_family and _chain_bp(left) == bp:
                left = _Chain(op_family, left.first, (*left.rest, (op, token.column, right)))
            else:
                left = _Chain(op_family, left, ((op, token.column, right),))
            family = op_family

    def prefix(self) -> tuple[_Node, str | None]:
        token = self.take()
        if token.kind == "num" or token.kind == "str":
            return _Literal(token.value, token.column), None
        if token.kind == "name":
            return _Name(token.text, token.column), None
        if token.kind == "op" and token.text in ("-", "!", "~"):
            self.nest(token)
            operand, _ = self.expression(_PREFIX_BP)
            self.depth -= 1
            return _Unary(token.text, operand, token.column), None
        if token.kind == "op" and token.text == "(":
            self.nest(token)
            inner, _ = self.expression(0)
            self.depth -= 1
            close = self.take()
            if not (close.kind == "op" and close.text == ")"):
                raise self.fail(close, f"expected ')', got {self.describe(close)}")
            return inner, None
        raise self.fail(token, f"expected a value, got {self.describe(token)}")


def _chain_bp(chain: _Chain) -> int:
    return _BINARY[chain.rest[0][0]][1]


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
        if isinstance(value, int) and not _INT64_MIN <= value <= _INT64_MAX:
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

    def read(self, node: _Name) -> Any:
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

    def evaluate(self, node: _Node) -> Any:
        if isinstance(node, _Literal):
            return node.value
        if isinstance(node, _Name):
            return self.read(node)
        if isinstance(node, _Unary):
            return self.unary(node)
        if isinstance(node, _Chain):
            if node.family == "compare":
                return self.compare(node)
            value = self.evaluate(node.first)
            for op, column, operand in node.rest:
                value = self.binary(op, value, self.evaluate(operand), column)
            return value
        if isinstance(node, _If):
            condition = self.evaluate(node.condition)
            if isinstance(condition, str):
                chosen = condition != ""
            elif _is_number(condition):
                chosen = _as_number(condition) != 0
            else:
                raise self.fail(node.column, f"'?' cannot test {_kind(condition)}")
            return self.evaluate(node.then if chosen else node.otherwise)
        return self.assign(node)

    def unary(self, node: _Unary) -> Any:
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
        if number.is_integer() and _INT64_MIN <= number <= _INT64_MAX:
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

    def compare(self, node: _Chain) -> bool:
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

    def assign(self, node: _Assign) -> Any:
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

    def converted(self, node: _Assign, old: Any, value: Any) -> Any:
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

    def compound(self, node: _Assign, old: Any, value: Any) -> Any:
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


def _walk(node: _Node) -> Iterator[_Node]:
    stack = [node]
    while stack:
        current = stack.pop()
        yield current
        if isinstance(current, _Unary):
            stack.append(current.operand)
        elif isinstance(current, _Chain):
            stack.append(current.first)
            stack.extend(operand for _, _, operand in current.rest)
        elif isinstance(current, _If):
            stack.extend((current.condition, current.then, current.otherwise))
        elif isinstance(current, _Assign):
            stack.append(current.value)


def _parse(source: str) -> tuple[_Node, ...]:
    if not isinstance(source, str):
        raise ScriptError(str(source), 1, f"a script must be text, got {type(source).__name__}")
    if len(source) > MAX_SOURCE_CHARS:
        raise ScriptError(
            source, MAX_SOURCE_CHARS + 1, f"script longer than {MAX_SOURCE_CHARS} characters"
        )
    return _Parser(source).statements()


@dataclass(frozen=True)
class Script:
    """A parsed script. Build it with :func:`parse_script` (or ``Script(source)``, which
    parses too and raises :class:`ScriptError`)."""

    source: str
    _statements: tuple[_Node, ...] = field(default=(), repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self._statements:
            object.__setattr__(self, "_statements", _parse(self.source))

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
            for node in _walk(statement):
                if isinstance(node, _Name):
                    found.add(node.key)
                elif isinstance(node, _Assign) and node.op not in (":=", "="):
                    found.add(node.key)
        return frozenset(found)

    def keys_written(self) -> frozenset[str]:
        """Keys the script may write: the targets of its assignments."""
        return frozenset(
            node.key
            for statement in self._statements
            for node in _walk(statement)
            if isinstance(node, _Assign)
        )


@lru_cache(maxsize=1024)
def _cached(source: str) -> Script:
    return Script(source, _parse(source))


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
