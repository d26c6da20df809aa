"""BT.CPP v4's scripting language (planner.bt_script), case by case from BT.CPP's documented
behaviour: precedence, typing, assignment, errors with their columns, and the bounds."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.bt_script import (
    MAX_DEPTH,
    MAX_SOURCE_CHARS,
    DictEnv,
    Script,
    ScriptError,
    ScriptRuntimeError,
    parse_script,
    truthy,
)

ENUMS = {"RED": 1, "BLUE": 3, "GREEN": 5}


def run(source: str, **values: Any) -> Any:
    return parse_script(source).evaluate(DictEnv(values, ENUMS))


# (script, blackboard, expected value)
VALUES: list[tuple[str, dict[str, Any], Any]] = [
    # literals
    ("628", {}, 628),
    ("0x100", {}, 256),
    ("0X1f", {}, 31),
    ("3.14", {}, 3.14),
    ("3.14e2", {}, 314.0),
    ("3e-2", {}, 0.03),
    ("'hello world '", {}, "hello world "),
    ("true", {}, True),
    ("false", {}, False),
    ("'true'", {}, "true"),
    # arithmetic, precedence, associativity
    ("1 + 2 * 3", {}, 7),
    ("(1 + 2) * 3", {}, 9),
    ("10 - 4 - 3", {}, 3),
    ("24 / 4 / 2", {}, 3.0),
    ("5 / 2", {}, 2.5),
    ("-2 * 3", {}, -6),
    ("- -2", {}, 2),
    ("-x", {"x": 6}, -6),
    ("2 - -3", {}, 5),
    ("1.5 + 1", {}, 2.5),
    ("true + 1", {}, 2),
    # bitwise
    ("5 & 3", {}, 1),
    ("5 | 3", {}, 7),
    ("5 ^ 3", {}, 6),
    ("~0", {}, -1),
    ("6 | 1 & 3", {}, 7),  # & binds tighter than |
    ("(6 / 2) & 1", {}, 1),  # an integral real is an integer here
    # strings
    ("'ab' + 'cd'", {}, "abcd"),
    ("'value: ' .. 10", {}, "value: 10"),
    ("2.5 .. 'x'", {}, "2.5x"),
    ("'a' .. (1 + 2)", {}, "a3"),
    ("'a' .. 'b' == 'ab'", {}, True),  # BT.CPP 4.10: .. binds tighter than ==
    ("'a' .. true", {}, "atrue"),
    # comparisons
    ("1 < 2", {}, True),
    ("2 <= 2", {}, True),
    ("3 > 4", {}, False),
    ("3 >= 4", {}, False),
    ("3 == 3.0", {}, True),
    ("0.1 + 0.2 == 0.3", {}, True),  # reals equal within float epsilon
    ("1 == 1.001", {}, False),
    ("3 != 4", {}, True),
    ("'hello' < 'world'", {}, True),
    ("'hello' == 'hello'", {}, True),
    ("'10' == 10", {}, True),  # a numeric string compares as a number
    ("10 < '9.5'", {}, False),
    ("'true' == 1", {}, True),
    ("'BLUE' == 3", {}, True),  # enum names in strings too
    ("1 < 2 < 3", {}, True),  # chained as a list
    ("3 < 2 < 5", {}, False),
    ("1 + 1 == 2", {}, True),
    # logic: && binds tighter than || (BT.CPP 4.10's ParserTest.OperatorPrecedence)
    ("true && false", {}, False),
    ("true || false", {}, True),
    ("true || false && false", {}, True),
    ("false || true && true", {}, True),
    ("false && true || true", {}, True),
    ("6 | 3 & 5", {}, 7),
    ("true && (6 | 0)", {}, True),
    # bit operators below + and - (4.10): (5 + 3) & 6, 7 & (2 + 1)
    ("5 + 3 & 6", {}, 0),
    ("7 & 2 + 1", {}, 3),
    ("!1 == 0", {}, True),  # a prefix binds tightest
    ("!false", {}, True),
    ("!0", {}, True),
    ("!3", {}, False),
    ("y == x && x == 3", {"x": 3, "y": 5}, False),
    ("y == x || x == 3", {"x": 3, "y": 5}, True),
    # ternary
    ("y == x ? 'T' : 'F'", {"x": 3, "y": 5}, "F"),
    ("y != x ? 'T' : 'F'", {"x": 3, "y": 5}, "T"),
    ("'' ? 1 : 2", {}, 2),
    ("'x' ? 1 : 2", {}, 1),
    ("0 ? 1 : 2 + 3", {}, 5),
    ("0 ? 2 : 0 ? 4 : 5", {}, 5),  # the else branch may be a ternary (4.10)
    ("1 ? 2 : 3 ? 4 : 5", {}, 2),
    ("1 ? (0 ? 'a' : 'b') : 'c'", {}, "b"),
    # enums and keys
    ("RED", {}, 1),
    ("GREEN + BLUE", {}, 8),
    ("RED", {"RED": 99}, 1),  # an enum wins over a key of the same name
    ("@RED", {"@RED": 99}, 99),  # a root key is never an enum
    ("@count + 1", {"@count": 4}, 5),
    # statements
    ("x := 3; y := 5; x + y", {}, 8),
    ("x := 1;", {}, 1),
    ("x := 1;\ny := 2", {}, 2),
    ("(x := 4) + 1", {}, 5),
]


@pytest.mark.parametrize(("source", "values", "expected"), VALUES)
def test_value(source: str, values: dict[str, Any], expected: Any) -> None:
    got = run(source, **values)
    assert type(got) is type(expected), f"{source!r} gave {got!r}"
    if isinstance(expected, float):
        assert got == pytest.approx(expected, rel=1e-12)
    else:
        assert got == expected


# (script, blackboard before, blackboard after)
ASSIGNMENTS: list[tuple[str, dict[str, Any], dict[str, Any]]] = [
    ("x := 3", {}, {"x": 3}),
    ("a := b := 1", {}, {"a": 1, "b": 1}),  # BT.CPP 4.10: the right side is an expression
    ("x := 3", {"x": 1}, {"x": 3}),
    ("x = 3", {"x": 1}, {"x": 3}),
    ("x += 1", {"x": 3}, {"x": 4}),
    ("x -= 1", {"x": 3}, {"x": 2}),
    ("x *= 2", {"x": 3}, {"x": 6}),
    ("x /= 2", {"x": 3}, {"x": 1.5}),
    ("s += 'b'", {"s": "a"}, {"s": "ab"}),
    ("x = '42'", {"x": 1}, {"x": 42}),  # a numeric string into a number entry
    ("x = RED", {"x": 0}, {"x": 1}),
    ("c := BLUE", {}, {"c": 3}),
    ("@r := 1; r := 2", {}, {"@r": 1, "r": 2}),
    ("v1 := true; v2 := !v1", {}, {"v1": True, "v2": False}),
    ("x := 'late'", {"x": None}, {"x": "late"}),  # an empty entry takes any type
]


@pytest.mark.parametrize(("source", "before", "after"), ASSIGNMENTS)
def test_assignment(source: str, before: dict[str, Any], after: dict[str, Any]) -> None:
    env = DictEnv(before, ENUMS)
    parse_script(source).evaluate(env)
    assert env.values == after


def test_assignment_returns_the_value_written() -> None:
    assert run("x += 2", x=1) == 3
    assert run("x := 'a'") == "a"


# (script, blackboard, column, reason pattern)
RUNTIME_ERRORS: list[tuple[str, dict[str, Any], int, str]] = [
    ("x + 1", {}, 1, "variable 'x' not found"),
    ("1 + @x", {"x": 1}, 5, "variable '@x' not found"),
    ("x < 0", {"x": None}, 1, "'x' is not initialised"),
    ("new_var = 69", {}, 9, r"'new_var' does not exist yet: use ':='"),
    ("n += 1", {}, 3, r"does not exist yet: use ':='"),
    ("n += 1", {"n": None}, 3, "not initialised"),
    ("'abc' == 1", {}, 7, "cannot compare string 'abc' with a number"),
    ("x = 'msg'", {"x": 1}, 3, "'x' holds a number; cannot assign string 'msg'"),
    ("s = 1.0", {"s": "a"}, 3, "'s' holds a string; cannot assign number 1"),
    ("s -= 'a'", {"s": "ab"}, 3, "'-=' is not defined for string"),
    ("x += 'a'", {"x": 1}, 3, "'\\+=' is not defined for number 1 and string"),
    ("'a' - 'b'", {}, 5, "'-' is not defined for string 'a' and string 'b'"),
    ("'a' + 1", {}, 5, "'\\+' is not defined"),
    ("'a' && true", {}, 5, "'&&' is not defined"),
    ("-'a'", {}, 1, "unary '-' needs a number"),
    ("!'a'", {}, 1, "unary '!' needs a number"),
    ("5 ^ 5.1", {}, 3, "'\\^' needs integers, got 5.1"),
    ("~1.5", {}, 1, "'~' needs integers"),
    ("1 / 0", {}, 3, "division by zero"),
    ("x /= 0", {"x": 1}, 3, "division by zero"),
    ("1e308 * 10", {}, 7, "numbers must stay finite"),
    ("0x7fffffffffffffff + 1", {}, 20, "overflows a 64-bit integer"),
    ("x *= 1e200", {"x": 1e200}, 3, "numbers must stay finite"),
    ("p == 1", {"p": [1]}, 3, "cannot compare a value of type list"),
]


@pytest.mark.parametrize(("source", "values", "column", "reason"), RUNTIME_ERRORS)
def test_runtime_error(source: str, values: dict[str, Any], column: int, reason: str) -> None:
    script = parse_script(source)
    with pytest.raises(ScriptRuntimeError, match=reason) as caught:
        script.evaluate(DictEnv(values, ENUMS))
    assert caught.value.column == column
    assert caught.value.source == source
    assert str(caught.value) == f"column {column}: {caught.value.reason}"


def test_failed_equals_assignment_creates_nothing() -> None:
    env = DictEnv({"a": 1})
    with pytest.raises(ScriptRuntimeError, match="use ':='"):
        parse_script("new_var = 69").evaluate(env)
    assert env.values == {"a": 1}


# (script, column, reason pattern)
SYNTAX_ERRORS: list[tuple[str, int, str]] = [
    ("x := ", 6, "expected a value, got the end of the script"),
    ("a == == b", 6, "expected a value, got '=='"),
    ("s := 'abc", 6, "unterminated string"),
    ("a # b", 3, "unexpected character '#'"),
    ("", 1, "empty script"),
    ("  ;  ", 1, "empty script"),
    ("1 2", 3, "expected an operator or ';', got '2'"),
    ("a and b", 3, "expected an operator or ';', got 'and'"),
    ("(1 + 2", 7, "expected '\\)', got the end"),
    ("1 +", 4, "expected a value"),
    ("65.", 4, "expected digits after the decimal point"),
    ("3foo", 2, "unexpected 'f' after the number 3"),
    ("0x", 1, "expected hex digits"),
    ("1e", 3, "expected digits in the exponent"),
    ("1e999", 1, "out of range"),
    ("99999999999999999999", 1, "does not fit in 64 bits"),
    ("@ x", 1, "expected a key name after '@'"),
    ("3 := 1", 3, "the left of ':=' must be a blackboard key"),
    ("a + b = 1", 7, "the left of '=' must be a blackboard key"),
    ("1 ? 2 3", 7, "expected ':'"),
    ("x := 1 ? 2 : 3 + 1 ?", 21, "expected a value, got the end of the script"),
    ('"double"', 1, "unexpected character '\"'"),
]


@pytest.mark.parametrize(("source", "column", "reason"), SYNTAX_ERRORS)
def test_syntax_error(source: str, column: int, reason: str) -> None:
    with pytest.raises(ScriptError, match=reason) as caught:
        parse_script(source)
    assert caught.value.column == column
    assert caught.value.source == source
    assert str(caught.value) == f"column {column}: {caught.value.reason}"


def test_parenthesised_mixes_are_accepted() -> None:
    assert run("(a + b) & c", a=1, b=2, c=7) == 3
    assert run("(a .. b) == 'xy'", a="x", b="y") is True


def test_script_longer_than_the_bound_is_refused() -> None:
    at_bound = "1" + "+1" * ((MAX_SOURCE_CHARS - 1) // 2)
    assert len(at_bound) <= MAX_SOURCE_CHARS
    assert run(at_bound) == (MAX_SOURCE_CHARS - 1) // 2 + 1
    with pytest.raises(ScriptError, match="longer than 10000 characters"):
        parse_script("1" + " " * MAX_SOURCE_CHARS)


@pytest.mark.parametrize(("opener", "closer"), [("(", ")"), ("-", ""), ("!", ""), ("1?", ":0")])
def test_nesting_deeper_than_the_bound_is_refused(opener: str, closer: str) -> None:
    deep_ok = opener * MAX_DEPTH + "1" + closer * MAX_DEPTH
    parse_script(deep_ok).evaluate(DictEnv())
    too_deep = opener * (MAX_DEPTH + 1) + "1" + closer * (MAX_DEPTH + 1)
    with pytest.raises(ScriptError, match="nesting deeper than 100"):
        parse_script(too_deep)


def test_very_deep_nesting_is_a_script_error_not_recursion() -> None:
    with pytest.raises(ScriptError, match="nesting deeper"):
        parse_script("(" * 4000 + "1" + ")" * 4000)


def test_keys_read_and_written() -> None:
    script = parse_script("a := b + @c; d += 1; e = RED ? f : 'g'")
    assert script.keys_written() == frozenset({"a", "d", "e"})
    assert script.keys_read() == frozenset({"b", "@c", "d", "RED", "f"})


def test_parse_is_pure_and_cached() -> None:
    assert parse_script("x := 1") is parse_script("x := 1")
    assert Script("x := 1") == parse_script("x := 1")
    with pytest.raises(ScriptError, match="expected a value"):
        Script("x :=")


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (True, True),
        (False, False),
        (0, False),
        (2, True),
        (0.0, False),
        (-0.5, True),
        ("true", True),
        ("FALSE", False),
        ("1", True),
        ("0", False),
    ],
)
def test_truthy(value: Any, expected: bool) -> None:
    assert truthy(value) is expected


@pytest.mark.parametrize("value", ["yes", "", [1], None])
def test_truthy_refuses_what_bt_cpp_cannot_cast(value: Any) -> None:
    with pytest.raises(ScriptRuntimeError, match="a condition must give a number or a boolean"):
        truthy(value)


_ALPHABET = st.sampled_from(
    list("abxy019 ._@'()?:;+-*/&|^~!=<>#\"\n\t") + [":=", "==", "&&", "||", "..", "0x", "e"]
)


@settings(max_examples=300, deadline=None)
@given(st.lists(_ALPHABET, max_size=40).map("".join))
def test_random_text_only_ever_raises_script_errors(source: str) -> None:
    try:
        script = parse_script(source)
    except ScriptError:
        return
    try:
        script.evaluate(DictEnv({"a": 1, "b": "s", "x": 2.5, "@y": 0}, ENUMS))
    except ScriptRuntimeError:
        pass


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=60))
def test_random_unicode_only_ever_raises_script_errors(source: str) -> None:
    try:
        parse_script(source).evaluate(DictEnv({"a": 1}))
    except (ScriptError, ScriptRuntimeError):
        pass


def test_errors_survive_pickling() -> None:
    import pickle

    for error in (ScriptError("x :=", 5, "expected a value"), ScriptRuntimeError("y", 1, "z")):
        back = pickle.loads(pickle.dumps(error))
        assert (type(back), back.source, back.column, back.reason, str(back)) == (
            type(error),
            error.source,
            error.column,
            error.reason,
            str(error),
        )


class _ScopedEnv:
    """A subtree blackboard over a root one, as a host would write it: '@key' goes to root."""

    def __init__(self) -> None:
        self.root: dict[str, Any] = {"speed": 2}
        self.local: dict[str, Any] = {}

    def _scope(self, key: str) -> tuple[dict[str, Any], str]:
        return (self.root, key[1:]) if key.startswith("@") else (self.local, key)

    def read(self, key: str) -> Any:
        scope, name = self._scope(key)
        return scope[name]

    def write(self, key: str, value: Any) -> None:
        scope, name = self._scope(key)
        scope[name] = value

    def exists(self, key: str) -> bool:
        scope, name = self._scope(key)
        return name in scope

    def enum(self, name: str) -> int | None:
        return {"FAST": 10}.get(name)


def test_a_host_environment_with_a_root_blackboard() -> None:
    env = _ScopedEnv()
    result = parse_script("@speed *= FAST; speed := @speed / 4; speed > 4 ? 'go' : 'wait'")
    assert result.evaluate(env) == "go"
    assert env.root == {"speed": 20}
    assert env.local == {"speed": pytest.approx(5.0)}
    with pytest.raises(ScriptRuntimeError, match="'@missing' does not exist yet"):
        parse_script("@missing = 1").evaluate(env)
