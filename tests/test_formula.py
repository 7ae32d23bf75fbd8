"""Tests for the safe formula evaluator (layershell.formula)."""

from __future__ import annotations

import math
import operator
import pickle

import numpy as np
import pytest

from layershell.formula import (
    DEFAULT_TOL,
    FUNCTIONS,
    MAX_LENGTH,
    Formula,
    FormulaError,
    compile_formula,
)

XYZ = ("x", "y", "z")


def ev(text: str, **values: object) -> np.ndarray:
    return compile_formula(text, XYZ)(**values)


# --- arithmetic -------------------------------------------------------------------


_ARITH = [
    ("1 + 2 * 3", lambda x, y, z: 1 + 2 * 3),
    ("(1 + 2) * 3", lambda x, y, z: (1 + 2) * 3),
    ("2 ** 3 ** 2", lambda x, y, z: 2 ** 3 ** 2),
    ("-2 ** 2", lambda x, y, z: -2 ** 2),
    ("(-2) ** 2", lambda x, y, z: (-2) ** 2),
    ("7 % 3", lambda x, y, z: 7 % 3),
    ("-7 % 3", lambda x, y, z: -7 % 3),
    ("10 / 4", lambda x, y, z: 10 / 4),
    ("1 - 2 - 3", lambda x, y, z: 1 - 2 - 3),
    ("2 * x + y / 4 - z ** 2", lambda x, y, z: 2 * x + y / 4 - z ** 2),
    ("x * -y + +z", lambda x, y, z: x * -y + +z),
    ("x % 0.75 * 3 - y / (z + 10)", lambda x, y, z: x % 0.75 * 3 - y / (z + 10)),
    ("2 ** -1", lambda x, y, z: 2 ** -1),
    ("1.5e3 * x", lambda x, y, z: 1.5e3 * x),
    ("y % z - x ** 0.5 / -z", lambda x, y, z: y % z - x ** 0.5 / -z),
]


@pytest.mark.parametrize("text,python", _ARITH, ids=[t for t, _ in _ARITH])
def test_arithmetic_matches_python(text: str, python) -> None:
    x, y, z = 1.25, -3.5, 2.0
    expected = python(x, y, z)
    result = ev(text, x=x, y=y, z=z)
    assert isinstance(result, np.ndarray)
    assert result.shape == ()
    assert float(result) == pytest.approx(expected, rel=1e-14, abs=0)


def test_constants_pi_e() -> None:
    assert float(ev("pi")) == math.pi
    assert float(ev("e")) == math.e
    assert float(ev("2 * pi * x", x=0.5)) == pytest.approx(math.pi)


def test_variables_used_and_metadata() -> None:
    f = compile_formula("x * pi + sin(z)", XYZ)
    assert isinstance(f, Formula)
    assert f.text == "x * pi + sin(z)"
    assert f.variables_used == {"x", "z"}
    assert compile_formula("1 + pi", XYZ).variables_used == set()
    with pytest.raises(Exception):
        f.text = "y"  # frozen


# --- vectorisation ----------------------------------------------------------------


def test_vectorised_over_arrays() -> None:
    x = np.linspace(-1.0, 1.0, 11)
    np.testing.assert_allclose(ev("3 * x ** 2 - 1", x=x), 3 * x**2 - 1)


def test_broadcasting() -> None:
    x = np.linspace(0.0, 1.0, 4)[:, None]
    y = np.linspace(0.0, 2.0, 3)[None, :]
    out = ev("x + 10 * y + z", x=x, y=y, z=1.0)
    assert out.shape == (4, 3)
    np.testing.assert_allclose(out, x + 10 * y + 1.0)


def test_unused_variables_take_part_in_broadcast() -> None:
    x = np.arange(5.0)
    y = np.zeros((2, 1))
    out = ev("x + 1", x=x, y=y)
    assert out.shape == (2, 5)
    np.testing.assert_allclose(out, np.broadcast_to(x + 1, (2, 5)))


@pytest.mark.parametrize("text,value", [("3", 3.0), ("2.5 * pi", 2.5 * math.pi), ("-1", -1.0)])
def test_constant_formula_has_input_shape(text: str, value: float) -> None:
    x = np.zeros((3, 4))
    out = ev(text, x=x, y=1.0)
    assert out.shape == (3, 4)
    np.testing.assert_allclose(out, np.full((3, 4), value))
    out[0, 0] = 99.0  # writable, independent array
    assert ev(text).shape == ()
    assert float(ev(text)) == value


def test_output_is_not_an_alias_of_input() -> None:
    x = np.arange(4.0)
    out = ev("x", x=x)
    np.testing.assert_array_equal(out, x)
    out[0] = 42.0
    assert x[0] == 0.0


def test_integer_inputs_and_lists() -> None:
    np.testing.assert_allclose(ev("x ** -1", x=[1, 2, 4]), [1.0, 0.5, 0.25])


# --- booleans and conditionals ----------------------------------------------------


def test_comparisons() -> None:
    x = np.array([-1.0, 0.0, 0.5, 1.0, 2.0])
    ops = {"<": operator.lt, "<=": operator.le, ">": operator.gt,
           ">=": operator.ge, "==": operator.eq, "!=": operator.ne}
    for op, func in ops.items():
        out = ev(f"x {op} 0.5", x=x)
        assert out.dtype == bool
        np.testing.assert_array_equal(out, func(x, 0.5))


def test_chained_comparison() -> None:
    x = np.array([-1.0, 0.0, 0.5, 1.0, 2.0])
    np.testing.assert_array_equal(ev("0 < x < 1", x=x), (0 < x) & (x < 1))
    np.testing.assert_array_equal(
        ev("-1 <= x < 1 <= 2", x=x), (-1 <= x) & (x < 1)
    )
    np.testing.assert_array_equal(ev("0 < x <= y", x=x, y=0.5), (0 < x) & (x <= 0.5))


def test_and_or_not() -> None:
    x = np.array([-1.0, 0.25, 0.75, 2.0])
    np.testing.assert_array_equal(ev("x > 0 and x < 1", x=x), (x > 0) & (x < 1))
    np.testing.assert_array_equal(ev("x < 0 or x > 1", x=x), (x < 0) | (x > 1))
    np.testing.assert_array_equal(ev("not x > 0", x=x), ~(x > 0))
    np.testing.assert_array_equal(
        ev("x < 0 or x > 0.5 and x < 1 or x == 2", x=x), [True, False, True, True]
    )
    np.testing.assert_array_equal(ev("not (x > 0 and not x > 1)", x=x), [True, False, False, True])


def test_conditional_expression_and_where() -> None:
    x = np.array([-2.0, -0.5, 0.5, 2.0])
    expected = np.where(x > 0, x, -10 * x)
    np.testing.assert_allclose(ev("x if x > 0 else -10 * x", x=x), expected)
    np.testing.assert_allclose(ev("where(x > 0, x, -10 * x)", x=x), expected)
    out = ev("1 if 0 < x < 1 else 0", x=x, y=np.zeros((2, 1)))
    assert out.shape == (2, 4)
    np.testing.assert_allclose(out[1], [0, 0, 1, 0])


def test_where_with_log_of_nonpositive_is_quiet() -> None:
    x = np.array([-1.0, 0.0, np.e])
    with np.errstate(all="raise"):
        np.testing.assert_allclose(ev("where(x > 0, log(x), 0)", x=x), [0.0, 0.0, 1.0])


def test_near_with_tol() -> None:
    f = compile_formula("near(x, 0.5)", XYZ)
    x = np.array([0.5, 0.5 + 1e-12, 0.5 + 1e-6, 0.6])
    np.testing.assert_array_equal(f(x=x), [True, True, False, False])
    np.testing.assert_array_equal(f(tol=1e-5, x=x), [True, True, True, False])
    np.testing.assert_array_equal(f(0.2, x=x), [True, True, True, True])
    assert DEFAULT_TOL == 1e-9
    assert bool(compile_formula("near(0.1 + 0.2, 0.3)", ())()) is True


# --- whitelisted functions --------------------------------------------------------

_U = np.array([0.1, 0.35, 0.8])
_V = np.array([-0.4, 0.7, 1.9])

_FUNC_CASES: dict[str, tuple[str, np.ndarray]] = {
    "abs": ("abs(y)", np.abs(_V)),
    "sqrt": ("sqrt(x)", np.sqrt(_U)),
    "exp": ("exp(y)", np.exp(_V)),
    "log": ("log(x)", np.log(_U)),
    "log10": ("log10(x)", np.log10(_U)),
    "sin": ("sin(y)", np.sin(_V)),
    "cos": ("cos(y)", np.cos(_V)),
    "tan": ("tan(y)", np.tan(_V)),
    "arcsin": ("arcsin(x)", np.arcsin(_U)),
    "asin": ("asin(x)", np.arcsin(_U)),
    "arccos": ("arccos(x)", np.arccos(_U)),
    "acos": ("acos(x)", np.arccos(_U)),
    "arctan": ("arctan(y)", np.arctan(_V)),
    "atan": ("atan(y)", np.arctan(_V)),
    "arctan2": ("arctan2(y, x)", np.arctan2(_V, _U)),
    "atan2": ("atan2(y, x)", np.arctan2(_V, _U)),
    "sinh": ("sinh(y)", np.sinh(_V)),
    "cosh": ("cosh(y)", np.cosh(_V)),
    "tanh": ("tanh(y)", np.tanh(_V)),
    "minimum": ("minimum(x, y)", np.minimum(_U, _V)),
    "min": ("min(x, y)", np.minimum(_U, _V)),
    "maximum": ("maximum(x, y)", np.maximum(_U, _V)),
    "max": ("max(x, y)", np.maximum(_U, _V)),
    "floor": ("floor(3 * y)", np.floor(3 * _V)),
    "ceil": ("ceil(3 * y)", np.ceil(3 * _V)),
    "hypot": ("hypot(x, y)", np.hypot(_U, _V)),
    "deg": ("deg(y)", np.degrees(_V)),
    "rad": ("rad(100 * y)", np.radians(100 * _V)),
    "where": ("where(y > 0, x, y)", np.where(_V > 0, _U, _V)),
    "near": ("near(x, 0.35)", np.isclose(_U, 0.35, rtol=0, atol=1e-9)),
}


def test_every_function_has_a_case() -> None:
    assert set(_FUNC_CASES) == set(FUNCTIONS)


@pytest.mark.parametrize("name", sorted(_FUNC_CASES))
def test_whitelisted_function(name: str) -> None:
    text, expected = _FUNC_CASES[name]
    out = ev(text, x=_U, y=_V)
    assert out.shape == expected.shape
    if expected.dtype == bool:
        np.testing.assert_array_equal(out, expected)
    else:
        np.testing.assert_allclose(out, expected, rtol=1e-15, atol=0)


def test_functions_with_scalars_and_broadcast() -> None:
    out = ev("max(x, 0.5) + sqrt(y)", x=np.array([0.0, 1.0]), y=np.array([[4.0], [9.0]]))
    np.testing.assert_allclose(out, [[2.5, 3.0], [3.5, 4.0]])


def test_pickle_roundtrip() -> None:
    f = compile_formula("x + sin(y)", XYZ)
    g = pickle.loads(pickle.dumps(f))
    assert g == f
    assert float(g(x=1.0, y=0.0)) == 1.0


# --- rejection --------------------------------------------------------------------


@pytest.mark.parametrize(
    "text,needles",
    [
        ("__import__('os')", ["__import__", "allowed functions", "sqrt"]),
        ('__import__("os").system("ls")', ["system"]),
        ("x.__class__", ["__class__", "attribute"]),
        ("x.__class__.__bases__[0]", ["subscript"]),
        ("[1,2][0]", ["subscript"]),
        ("[1, 2]", ["list"]),
        ("(1, 2)", ["tuple"]),
        ("lambda: 1", ["lambda"]),
        ("open('f')", ["open", "allowed functions"]),
        ("'abc'", ["'abc'", "str"]),
        ("b'abc'", ["bytes"]),
        ("1j", ["complex"]),
        ("True", ["bool"]),
        ("sqrt(x=1)", ["sqrt", "x="]),
        ("sqrt(*x)", ["starred"]),
        ("x + foo", ["'foo'", "allowed names: x, y, z, pi, e"]),
        ("sqrt", ["'sqrt'", "called"]),
        ("sqrt(x, y)", ["'sqrt'", "1 argument"]),
        ("where(x, y)", ["'where'", "3 arguments"]),
        ("x // 2", ["'//'"]),
        ("x & 1", ["'&'"]),
        ("~x", ["'~'"]),
        ("x is None", ["'is'"]),
        ("x in y", ["'in'"]),
        ("[x for x in y]", ["comprehension"]),
        ("(y := 2)", ["walrus"]),
        ("f'{x}'", ["f-string"]),
        ("{1: 2}", ["dict"]),
        ("sin.__call__(x)", ["__call__"]),
        ("(lambda: 1)()", ["named functions"]),
        ("x(1)", ["'x'", "not allowed"]),
    ],
)
def test_rejected(text: str, needles: list[str]) -> None:
    with pytest.raises(FormulaError) as info:
        compile_formula(text, XYZ)
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith(f"formula {text!r}: ")
    for needle in needles:
        assert needle in msg, (needle, msg)


def test_error_message_examples() -> None:
    with pytest.raises(FormulaError, match=r"^formula 'x \+ foo': unknown name 'foo'; "
                       r"allowed names: x, y, z, pi, e$"):
        compile_formula("x + foo", XYZ)
    with pytest.raises(FormulaError, match=r"^formula 'x \+': syntax error at column 4$"):
        compile_formula("x +", XYZ)
    assert issubclass(FormulaError, ValueError)


@pytest.mark.parametrize("text", ["x +", "sin(x", "x y", "1 +* 2", "x ==== 1", ")"])
def test_syntax_error(text: str) -> None:
    with pytest.raises(FormulaError, match="syntax error at column"):
        compile_formula(text, XYZ)


def test_too_long_formula() -> None:
    text = "+".join(["x"] * (MAX_LENGTH // 2 + 1))
    assert len(text) > MAX_LENGTH
    with pytest.raises(FormulaError, match="too long"):
        compile_formula(text, XYZ)


def test_too_deep_formula() -> None:
    with pytest.raises(FormulaError, match="nested too deeply"):
        compile_formula("-" * 60 + "x", XYZ)
    with pytest.raises(FormulaError, match="nested too deeply"):
        compile_formula("+".join(["1"] * 100), XYZ)
    with pytest.raises(FormulaError):  # deepest the parser can be pushed within the limit
        compile_formula("-" * (MAX_LENGTH - 1) + "x", XYZ)
    compile_formula("-" * 40 + "x", XYZ)  # moderate nesting is fine


def test_empty_and_non_string() -> None:
    with pytest.raises(FormulaError, match="empty"):
        compile_formula("   ", XYZ)
    with pytest.raises(FormulaError):
        compile_formula(42, XYZ)  # type: ignore[arg-type]


def test_reserved_variable_names() -> None:
    for bad in ("pi", "tol", "for", "1x"):
        with pytest.raises(FormulaError, match=repr(bad)):
            compile_formula("1", ("x", bad))


def test_missing_variable_at_call_time() -> None:
    f = compile_formula("x + y", XYZ)
    with pytest.raises(FormulaError, match="missing value for variable 'y'"):
        f(x=1.0)
    with pytest.raises(FormulaError, match="'x', 'y'"):
        f()


def test_bad_values_at_call_time() -> None:
    f = compile_formula("x + y", XYZ)
    with pytest.raises(FormulaError, match="unexpected value for 'w'"):
        f(x=1.0, y=2.0, w=3.0)
    with pytest.raises(FormulaError, match="broadcast"):
        f(x=np.zeros(3), y=np.zeros(4))
    with pytest.raises(FormulaError, match="not numeric"):
        f(x="abc", y=1.0)


def test_leading_whitespace_and_multiline() -> None:
    assert float(ev("  x + 1", x=1.0)) == 2.0
    assert float(ev("(x +\n 1)", x=1.0)) == 2.0
    with pytest.raises(FormulaError, match="syntax error at column 6"):
        compile_formula("  x +", XYZ)
