"""The syntax half of :mod:`planner.bt_script`: errors, tokenizer and Pratt parser of
BT.CPP v4's scripting language, giving a flat syntax tree (binary chains as lists, so depth
follows the parentheses and prefixes only, which :data:`MAX_DEPTH` bounds)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

MAX_SOURCE_CHARS = 10_000
MAX_DEPTH = 100
INT64_MIN = -(2**63)
INT64_MAX = 2**63 - 1


class _AtColumn(Exception):
    """What both script errors carry: the script, the 1-based column and the reason."""

    def __init__(self, source: str, column: int, reason: str) -> None:
        super().__init__(f"column {column}: {reason}")
        self.source = source
        self.column = column
        self.reason = reason

    def __reduce__(self) -> tuple[Any, tuple[str, int, str]]:
        # picklable for worker processes: the default would call __init__(message)
        return (type(self), (self.source, self.column, self.reason))


class ScriptError(_AtColumn, ValueError):
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


class ScriptRuntimeError(_AtColumn, RuntimeError):
    """A script that parsed but cannot run on these values: an undefined key, ``=`` on a
    missing entry, operands of the wrong type, an overflow. Same attributes as
    :class:`ScriptError`; ``column`` points at the operator or the key."""


# ---------------------------------------------------------------------------------------------
# Tokens

#: longest first, so that ``:=`` is one token and not ``:`` then ``=``
_OPERATORS = tuple(":= += -= *= /= == != <= >= && || .. = < > + - * / & | ^ ~ ! ? : ( ) ;".split())


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
    if isinstance(value, int) and not INT64_MIN <= value <= INT64_MAX:
        raise ScriptError(source, col, f"integer {source[i:j]} does not fit in 64 bits")
    tokens.append(_Token("num", source[i:j], col, value))
    return j


# ---------------------------------------------------------------------------------------------
# Syntax tree. Binary chains are flat lists so that a long ``1+1+...+1`` never recurses deeply.


@dataclass(frozen=True)
class Literal:
    value: Any
    column: int


@dataclass(frozen=True)
class Name:
    key: str
    column: int


@dataclass(frozen=True)
class Unary:
    op: str
    operand: Node
    column: int


@dataclass(frozen=True)
class Chain:
    """``first op1 x1 op2 x2 ...``, folded left (or, for comparisons, as a list)."""

    family: str  # "math", "bit", "concat", "compare", "logic"
    first: Node
    rest: tuple[tuple[str, int, Node], ...]  # (operator, column, operand)


@dataclass(frozen=True)
class If:
    condition: Node
    then: Node
    otherwise: Node
    column: int


@dataclass(frozen=True)
class Assign:
    op: str
    key: str
    value: Node
    column: int


Node = Literal | Name | Unary | Chain | If | Assign

_ASSIGN_OPS = (":=", "=", "+=", "-=", "*=", "/=")
#: operator -> (family, left binding power), BT.CPP 4.10's (its Pratt parser, 4.9 on): ``||``
#: below ``&&`` below the comparisons below ``|`` ``^`` below ``&`` below ``+`` ``-`` ``..``
#: below ``*`` ``/``; each left-associative (comparisons chain).
_BINARY: dict[str, tuple[str, int]] = {
    "||": ("logic", 6),
    "&&": ("logic", 8),
    "==": ("compare", 10),
    "!=": ("compare", 10),
    "<": ("compare", 10),
    "<=": ("compare", 10),
    ">": ("compare", 10),
    ">=": ("compare", 10),
    "|": ("bit", 12),
    "^": ("bit", 12),
    "&": ("bit", 14),
    "+": ("math", 16),
    "-": ("math", 16),
    "..": ("concat", 16),
    "*": ("math", 18),
    "/": ("math", 18),
}
_ASSIGN_BP = 2
_TERNARY_BP = 4
_PREFIX_BP = 20


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

    def statements(self) -> tuple[Node, ...]:
        found: list[Node] = []
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

    def expression(self, min_bp: int) -> tuple[Node, str | None]:
        """Pratt loop; returns the node and the family of its top operator (None for an atom,
        a parenthesised expression or a unary operator)."""
        left, family = self.prefix()
        while True:
            token = self.peek()
            if token.kind != "op":
                return left, family
            op = token.text
            if op in _ASSIGN_OPS:
                # As BT.CPP 4.10: the right side is a whole expression (so ``a := b := 1``
                # sets both), and nothing follows an assignment but ``;`` or a ``)``.
                if min_bp > _ASSIGN_BP:
                    return left, family
                if not isinstance(left, Name) or family is not None:
                    raise self.fail(token, f"the left of '{op}' must be a blackboard key")
                self.take()
                self.nest(token)
                value, _ = self.expression(0)
                self.depth -= 1
                return Assign(op, left.key, value, token.column), "assign"
            if op == "?":
                # As BT.CPP 4.10: ``c ? a : b ? x : y`` is ``c ? a : (b ? x : y)``.
                if min_bp > _TERNARY_BP:
                    return left, family
                self.take()
                self.nest(token)
                then, _ = self.expression(0)
                colon = self.take()
                if not (colon.kind == "op" and colon.text == ":"):
                    raise self.fail(colon, f"expected ':' of '?', got {self.describe(colon)}")
                otherwise, _ = self.expression(_TERNARY_BP)
                self.depth -= 1
                return If(left, then, otherwise, token.column), "if"
            if op not in _BINARY:
                return left, family
            op_family, bp = _BINARY[op]
            if bp < min_bp:
                return left, family
            self.take()
            right, _ = self.expression(bp + 1)
            if isinstance(left, Chain) and family == op_family and _chain_bp(left) == bp:
                left = Chain(op_family, left.first, (*left.rest, (op, token.column, right)))
            else:
                left = Chain(op_family, left, ((op, token.column, right),))
            family = op_family

    def prefix(self) -> tuple[Node, str | None]:
        token = self.take()
        if token.kind == "num" or token.kind == "str":
            return Literal(token.value, token.column), None
        if token.kind == "name":
            return Name(token.text, token.column), None
        if token.kind == "op" and token.text in ("-", "!", "~"):
            self.nest(token)
            operand, _ = self.expression(_PREFIX_BP)
            self.depth -= 1
            return Unary(token.text, operand, token.column), None
        if token.kind == "op" and token.text == "(":
            self.nest(token)
            inner, _ = self.expression(0)
            self.depth -= 1
            close = self.take()
            if not (close.kind == "op" and close.text == ")"):
                raise self.fail(close, f"expected ')', got {self.describe(close)}")
            return inner, None
        raise self.fail(token, f"expected a value, got {self.describe(token)}")


def _chain_bp(chain: Chain) -> int:
    return _BINARY[chain.rest[0][0]][1]


def walk(node: Node) -> Iterator[Node]:
    stack = [node]
    while stack:
        current = stack.pop()
        yield current
        if isinstance(current, Unary):
            stack.append(current.operand)
        elif isinstance(current, Chain):
            stack.append(current.first)
            stack.extend(operand for _, _, operand in current.rest)
        elif isinstance(current, If):
            stack.extend((current.condition, current.then, current.otherwise))
        elif isinstance(current, Assign):
            stack.append(current.value)


def parse(source: str) -> tuple[Node, ...]:
    if not isinstance(source, str):
        raise ScriptError(str(source), 1, f"a script must be text, got {type(source).__name__}")
    if len(source) > MAX_SOURCE_CHARS:
        raise ScriptError(
            source, MAX_SOURCE_CHARS + 1, f"script longer than {MAX_SOURCE_CHARS} characters"
        )
    return _Parser(source).statements()
