"""Safe, vectorised evaluation of small arithmetic formulas from user model files.

Formulas (e.g. ``"where(x < 0.5, 1.0, 2.0) * sin(pi * y)"``) are parsed with
:mod:`ast` in ``eval`` mode and checked node by node against a whitelist; the
accepted tree is compiled once into nested Python closures that evaluate with
NumPy. File content is never passed to ``eval``/``exec``.

Allowed syntax: int/float literals; the declared variables and the constants
``pi`` and ``e``; unary ``+ - not``; binary ``+ - * / ** %``; comparisons
``< <= > >= == !=`` (chains such as ``0 < x < 1`` included); ``and``/``or``;
``a if c else b``; and calls (positional arguments only) to the functions in
:data:`FUNCTIONS`. Boolean operators act element-wise (``np.logical_*``) and
the conditional expression maps to ``np.where`` (both branches are evaluated).
"""

from __future__ import annotations

import ast
import keyword
import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

__all__ = [
    "DEFAULT_TOL",
    "MAX_DEPTH",
    "MAX_LENGTH",
    "FUNCTIONS",
    "CONSTANTS",
    "Formula",
    "FormulaError",
    "compile_formula",
]

#: Default tolerance of ``near(a, b)`` (``|a - b| <= tol``).
DEFAULT_TOL: float = 1e-9
#: Longest accepted formula text, in characters.
MAX_LENGTH: int = 2000
#: Deepest accepted nesting of expression nodes in the AST.
MAX_DEPTH: int = 50

#: Named constants usable in every formula.
CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

# Evaluation environment: variable name -> float array.
_Env = dict[str, np.ndarray]
# A compiled node: (environment, tol) -> value.
_Node = Callable[[_Env, float], Any]


def _near(a: Any, b: Any, tol: float) -> Any:
    return np.abs(np.subtract(a, b)) <= tol


#: Whitelisted functions: name -> (number of positional arguments, implementation).
#: ``near`` additionally receives the evaluation tolerance as its last argument.
FUNCTIONS: dict[str, tuple[int, Callable[..., Any]]] = {
    "abs": (1, np.abs),
    "sqrt": (1, np.sqrt),
    "exp": (1, np.exp),
    "log": (1, np.log),
    "log10": (1, np.log10),
    "sin": (1, np.sin),
    "cos": (1, np.cos),
    "tan": (1, np.tan),
    "arcsin": (1, np.arcsin),
    "asin": (1, np.arcsin),
    "arccos": (1, np.arccos),
    "acos": (1, np.arccos),
    "arctan": (1, np.arctan),
    "atan": (1, np.arctan),
    "arctan2": (2, np.arctan2),
    "atan2": (2, np.arctan2),
    "sinh": (1, np.sinh),
    "cosh": (1, np.cosh),
    "tanh": (1, np.tanh),
    "minimum": (2, np.minimum),
    "min": (2, np.minimum),
    "maximum": (2, np.maximum),
    "max": (2, np.maximum),
    "floor": (1, np.floor),
    "ceil": (1, np.ceil),
    "hypot": (2, np.hypot),
    "deg": (1, np.degrees),
    "rad": (1, np.radians),
    "where": (3, np.where),
    "near": (2, _near),
}

_BINOPS: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.true_divide,
    ast.Pow: np.power,
    ast.Mod: np.mod,
}
_BINOP_SYMBOLS: dict[type[ast.operator], str] = {
    ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**",
    ast.Mod: "%", ast.FloorDiv: "//", ast.MatMult: "@", ast.LShift: "<<",
    ast.RShift: ">>", ast.BitOr: "|", ast.BitXor: "^", ast.BitAnd: "&",
}
_CMPOPS: dict[type[ast.cmpop], Callable[[Any, Any], Any]] = {
    ast.Lt: np.less,
    ast.LtE: np.less_equal,
    ast.Gt: np.greater,
    ast.GtE: np.greater_equal,
    ast.Eq: np.equal,
    ast.NotEq: np.not_equal,
}
_CMPOP_SYMBOLS: dict[type[ast.cmpop], str] = {
    ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==",
    ast.NotEq: "!=", ast.Is: "is", ast.IsNot: "is not", ast.In: "in",
    ast.NotIn: "not in",
}

_ALLOWED_SYNTAX = (
    "numbers, variable names, pi, e, + - * / ** %, comparisons (< <= > >= == !=), "
    "and/or/not, 'a if c else b', and calls to whitelisted functions"
)

# Human-readable names of rejected node types.
_NODE_NAMES: dict[str, str] = {
    "Attribute": "attribute access",
    "Subscript": "subscript ('[...]')",
    "Slice": "slice",
    "Lambda": "lambda",
    "ListComp": "list comprehension",
    "SetComp": "set comprehension",
    "DictComp": "dict comprehension",
    "GeneratorExp": "generator expression",
    "NamedExpr": "walrus assignment (':=')",
    "JoinedStr": "f-string",
    "FormattedValue": "f-string",
    "List": "list display",
    "Tuple": "tuple",
    "Set": "set display",
    "Dict": "dict display",
    "Starred": "starred argument",
    "Await": "await",
    "Yield": "yield",
    "YieldFrom": "yield from",
}


class FormulaError(ValueError):
    """A formula is invalid, or cannot be evaluated with the given values."""


def _quote(text: str, limit: int = 80) -> str:
    """``repr`` of the formula text, shortened for long formulas."""
    if len(text) > limit:
        return repr(text[:limit]) + "..."
    return repr(text)


@dataclass(frozen=True)
class Formula:
    """A compiled, safely evaluable formula.

    Attributes:
        text: the original formula text.
        variables: the variable names the formula was allowed to use.
        variables_used: the variable names it actually references.
    """

    text: str
    variables: tuple[str, ...]
    variables_used: frozenset[str]
    _evaluate: _Node = field(repr=False, compare=False)

    def __call__(self, tol: float = DEFAULT_TOL, **values: Any) -> np.ndarray:
        """Evaluate element-wise on ``values`` (arrays or scalars), broadcast together.

        Every referenced variable needs a value; values for declared but unused
        variables still take part in the broadcast. ``tol`` is the tolerance of
        ``near``. Returns a new array of the broadcast shape of all values.
        """
        missing = sorted(self.variables_used.difference(values))
        if missing:
            raise FormulaError(
                f"formula {_quote(self.text)}: missing value for variable "
                f"{', '.join(repr(m) for m in missing)}"
            )
        unknown = sorted(set(values).difference(self.variables))
        if unknown:
            raise FormulaError(
                f"formula {_quote(self.text)}: unexpected value for "
                f"{', '.join(repr(u) for u in unknown)}; formula variables are: "
                f"{', '.join(self.variables) or '(none)'}"
            )
        env: _Env = {}
        for name, value in values.items():
            try:
                env[name] = np.asarray(value, dtype=float)
            except (TypeError, ValueError) as exc:
                raise FormulaError(
                    f"formula {_quote(self.text)}: value for {name!r} is not numeric ({exc})"
                ) from None
        try:
            shape = np.broadcast_shapes(*(a.shape for a in env.values()))
        except ValueError:
            shapes = ", ".join(f"{k} {a.shape}" for k, a in env.items())
            raise FormulaError(
                f"formula {_quote(self.text)}: cannot broadcast values together: {shapes}"
            ) from None
        with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
            result = np.asarray(self._evaluate(env, float(tol)))
        if result.shape != shape or any(result is a for a in env.values()):
            result = np.array(np.broadcast_to(result, shape))
        return result

    def __reduce__(self) -> tuple[Any, ...]:
        # Closures do not pickle; rebuild from the text instead.
        return (compile_formula, (self.text, self.variables))


def compile_formula(text: str, variables: tuple[str, ...]) -> Formula:
    """Parse and validate ``text`` and compile it into a :class:`Formula`.

    ``variables`` are the names the formula may reference (besides ``pi``
    and ``e``). Raises :class:`FormulaError` for anything outside the whitelist.
    """
    if not isinstance(text, str):
        raise FormulaError(f"formula {text!r}: must be a string, got {type(text).__name__}")
    variables = tuple(variables)
    for name in variables:
        if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
            raise FormulaError(f"formula {_quote(text)}: invalid variable name {name!r}")
        if name in CONSTANTS or name == "tol":
            raise FormulaError(
                f"formula {_quote(text)}: variable name {name!r} is reserved "
                f"(constants: {', '.join(CONSTANTS)}; 'tol' is the near() tolerance)"
            )
    if len(text) > MAX_LENGTH:
        raise FormulaError(
            f"formula {_quote(text, 40)}: too long ({len(text)} characters; "
            f"at most {MAX_LENGTH} allowed)"
        )
    if not text.strip():
        raise FormulaError(f"formula {_quote(text)}: empty formula")
    tree = _parse(text)
    _check_depth(text, tree)
    compiler = _Compiler(text, variables)
    evaluate = compiler.compile(tree.body)
    return Formula(
        text=text,
        variables=variables,
        variables_used=frozenset(compiler.used),
        _evaluate=evaluate,
    )


def _parse(text: str) -> ast.Expression:
    """Parse in ``eval`` mode, turning every parser failure into FormulaError."""
    stripped = text.lstrip(" \t")
    lead = len(text) - len(stripped)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return ast.parse(stripped, mode="eval")
    except SyntaxError as exc:
        lineno = exc.lineno or 1
        lines = stripped.splitlines() or [""]
        line = lines[min(lineno, len(lines)) - 1]
        col = exc.offset if exc.offset and exc.offset > 0 else len(line.rstrip()) + 1
        if lineno == 1:
            col += lead
        where = f"column {col}" if lineno == 1 else f"line {lineno}, column {col}"
        reason = f" ({exc.msg})" if exc.msg and exc.msg != "invalid syntax" else ""
        raise FormulaError(
            f"formula {_quote(text)}: syntax error at {where}{reason}"
        ) from None
    except (ValueError, RecursionError, MemoryError) as exc:
        raise FormulaError(f"formula {_quote(text)}: cannot parse ({exc})") from None


def _check_depth(text: str, tree: ast.AST) -> None:
    """Reject expression trees nested deeper than MAX_DEPTH (iteratively)."""
    stack: list[tuple[ast.AST, int]] = [(tree, 0)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, ast.expr):
            depth += 1
            if depth > MAX_DEPTH:
                raise FormulaError(
                    f"formula {_quote(text)}: expression nested too deeply "
                    f"(more than {MAX_DEPTH} levels)"
                )
        stack.extend((child, depth) for child in ast.iter_child_nodes(node))


class _Compiler:
    """Validates AST nodes and turns them into evaluation closures."""

    def __init__(self, text: str, variables: tuple[str, ...]) -> None:
        self.text = text
        self.variables = variables
        self.used: set[str] = set()

    def error(self, message: str) -> FormulaError:
        return FormulaError(f"formula {_quote(self.text)}: {message}")

    def compile(self, node: ast.AST) -> _Node:
        method = getattr(self, f"_compile_{type(node).__name__}", None)
        if method is None:
            what = _NODE_NAMES.get(type(node).__name__, f"syntax '{type(node).__name__}'")
            detail = ""
            if isinstance(node, ast.Attribute):
                detail = f" ('.{node.attr}')"
            raise self.error(f"{what}{detail} is not allowed; allowed: {_ALLOWED_SYNTAX}")
        return method(node)

    # --- leaves ---------------------------------------------------------------

    def _compile_Constant(self, node: ast.Constant) -> _Node:
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            kind = type(value).__name__
            shown = repr(value)
            if len(shown) > 40:
                shown = shown[:40] + "..."
            raise self.error(
                f"{kind} constant {shown} is not allowed; only int/float numbers are"
            )
        number = np.float64(value)
        return lambda env, tol: number

    def _compile_Name(self, node: ast.Name) -> _Node:
        name = node.id
        if name in self.variables:
            self.used.add(name)
            return lambda env, tol: env[name]
        if name in CONSTANTS:
            number = np.float64(CONSTANTS[name])
            return lambda env, tol: number
        hint = " (functions must be called, e.g. sqrt(x))" if name in FUNCTIONS else ""
        allowed = ", ".join((*self.variables, *CONSTANTS))
        raise self.error(f"unknown name {name!r}{hint}; allowed names: {allowed}")

    # --- operators --------------------------------------------------------------

    def _compile_UnaryOp(self, node: ast.UnaryOp) -> _Node:
        operand = self.compile(node.operand)
        if isinstance(node.op, ast.USub):
            return lambda env, tol: np.negative(operand(env, tol))
        if isinstance(node.op, ast.UAdd):
            return lambda env, tol: np.positive(operand(env, tol))
        if isinstance(node.op, ast.Not):
            return lambda env, tol: np.logical_not(operand(env, tol))
        raise self.error("unary operator '~' is not allowed; allowed unary operators: + - not")

    def _compile_BinOp(self, node: ast.BinOp) -> _Node:
        func = _BINOPS.get(type(node.op))
        if func is None:
            symbol = _BINOP_SYMBOLS.get(type(node.op), type(node.op).__name__)
            raise self.error(
                f"operator '{symbol}' is not allowed; allowed operators: + - * / ** %"
            )
        left = self.compile(node.left)
        right = self.compile(node.right)
        return lambda env, tol: func(left(env, tol), right(env, tol))

    def _compile_Compare(self, node: ast.Compare) -> _Node:
        funcs = []
        for op in node.ops:
            func = _CMPOPS.get(type(op))
            if func is None:
                symbol = _CMPOP_SYMBOLS.get(type(op), type(op).__name__)
                raise self.error(
                    f"comparison '{symbol}' is not allowed; allowed comparisons: "
                    "< <= > >= == !="
                )
            funcs.append(func)
        operands = [self.compile(node.left)] + [self.compile(c) for c in node.comparators]
        if len(funcs) == 1:
            func, (left, right) = funcs[0], operands
            return lambda env, tol: func(left(env, tol), right(env, tol))

        def chain(env: _Env, tol: float) -> Any:
            values = [operand(env, tol) for operand in operands]
            result = funcs[0](values[0], values[1])
            for i in range(1, len(funcs)):
                result = np.logical_and(result, funcs[i](values[i], values[i + 1]))
            return result

        return chain

    def _compile_BoolOp(self, node: ast.BoolOp) -> _Node:
        combine = np.logical_and if isinstance(node.op, ast.And) else np.logical_or
        parts = [self.compile(v) for v in node.values]

        def boolop(env: _Env, tol: float) -> Any:
            result = parts[0](env, tol)
            for part in parts[1:]:
                result = combine(result, part(env, tol))
            return result

        return boolop

    def _compile_IfExp(self, node: ast.IfExp) -> _Node:
        cond = self.compile(node.test)
        then = self.compile(node.body)
        other = self.compile(node.orelse)
        return lambda env, tol: np.where(cond(env, tol), then(env, tol), other(env, tol))

    # --- calls ------------------------------------------------------------------

    def _compile_Call(self, node: ast.Call) -> _Node:
        allowed = ", ".join(FUNCTIONS)
        if not isinstance(node.func, ast.Name):
            if isinstance(node.func, ast.Attribute):
                raise self.error(
                    f"attribute access ('.{node.func.attr}') is not allowed; "
                    f"call functions by name: {allowed}"
                )
            raise self.error(f"only calls of named functions are allowed: {allowed}")
        name = node.func.id
        if name not in FUNCTIONS:
            raise self.error(f"function {name!r} is not allowed; allowed functions: {allowed}")
        if node.keywords:
            kw = node.keywords[0]
            shown = f"'{kw.arg}='" if kw.arg is not None else "'**'"
            raise self.error(
                f"keyword argument {shown} in call to {name!r} is not allowed; "
                "pass arguments by position"
            )
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self.error(f"starred argument in call to {name!r} is not allowed")
        nargs, func = FUNCTIONS[name]
        if len(node.args) != nargs:
            plural = "s" if nargs != 1 else ""
            raise self.error(
                f"function {name!r} takes {nargs} argument{plural}, got {len(node.args)}"
            )
        args = [self.compile(a) for a in node.args]
        if name == "near":
            a, b = args
            return lambda env, tol: _near(a(env, tol), b(env, tol), tol)
        if nargs == 1:
            (a,) = args
            return lambda env, tol: func(a(env, tol))
        if nargs == 2:
            a, b = args
            return lambda env, tol: func(a(env, tol), b(env, tol))
        return lambda env, tol: func(*(arg(env, tol) for arg in args))
