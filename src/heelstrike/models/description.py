"""Declarative descriptions of planar tree-structured walkers.

A walker is a *description*, not a derivation: a tree of rigid links connected by revolute
joints, two convex feet (circular arcs, or profiles given by their support function) and
optional point masses, with named numeric parameters. The
builder (:mod:`heelstrike.models.builder`) derives the equations of motion from it.

The file format (every table and key, types, units, defaults, an example per feature, and the
errors a file is refused with) is documented on the page :doc:`/walker_files` of the
documentation site (source ``docs/walker_files.rst``). In short, with the paper's conventions:
angles are absolute, from the ground normal, counter-clockwise positive, and walking is towards
``-x``; a point on a link is ``(along, offset)`` from its proximal point; the coordinates are
``q = (x, y, theta_root, q_1, ..., q_k)``: the stance foot's arc centre, the root link's
absolute angle, then the relative joint angles ``theta_child - theta_parent`` in tree order.
Numeric fields take a number or an expression string in the parameters (``"l - R"``), parsed
safely (numbers, parameter names, ``+ - * / **``, ``pi``, ``sqrt``, ``sin``, ``cos``).

Walker files are data: nothing in them is ever executed or pasted into code. Parameter names
must be ASCII identifiers (not keywords, not reserved); expressions are bounded in length,
depth and exponent size (see :func:`check_parameter_name` and the ``MAX_*`` constants).
"""

from __future__ import annotations

import ast
import functools
import json
import keyword
import math
import operator
import os
import re
import stat
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._typing import FloatArray

__all__ = [
    "PROFILE_ANGLE",
    "EventsSpec",
    "Expr",
    "FootSpec",
    "JointSpec",
    "LinkSpec",
    "ModelDescriptionError",
    "PointMassSpec",
    "PostureLawSpec",
    "PoweredSpec",
    "WalkerDescription",
    "check_parameter_name",
    "check_profile",
    "constraint_holds",
    "evaluate_expression",
    "parameter_units",
    "parse_description",
    "read_description",
    "rolling_radius",
    "support_function",
]

#: A number or an expression string in the walker's parameters.
Expr = float | str


class ModelDescriptionError(ValueError):
    """A walker description is malformed; the message starts with the offending field path."""


# -- safe expressions ---------------------------------------------------------------------------

_BINOPS: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
}
_FUNCS = ("sqrt", "sin", "cos")

#: Longest expression string accepted (characters).
MAX_EXPRESSION_LENGTH = 400
#: Deepest expression tree accepted (nested operations).
MAX_EXPRESSION_DEPTH = 24
#: Largest absolute exponent accepted in ``a ** k`` (``k`` must be a number).
MAX_EXPONENT = 16.0
#: Largest absolute integer literal accepted (beyond it floats lose integers anyway).
MAX_INTEGER_LITERAL = 2**53
#: Largest magnitude of a parameter value or an evaluated field (SI units): a walker of
#: 1e12 kg or 1e12 m is no machine, and its energies (masses times squared lengths and speeds,
#: their products in the mass matrix's determinant) would leave the floating-point range.
MAX_FIELD_MAGNITUDE = 1e12
#: Most links a walker may have (derivation time grows steeply with the tree).
MAX_LINKS = 16
#: Largest walker file read (bytes).
MAX_DESCRIPTION_BYTES = 1 << 20

#: Names a parameter may not take: the expression functions, ``pi``, the simulation's ground
#: ``slope`` and keyword arguments of the loading functions.
RESERVED_PARAMETER_NAMES = frozenset(
    {"pi", *_FUNCS, "slope", "use_cache", "description", "name_or_path"}
)
_COMPARE_OPS = (ast.Lt, ast.LtE, ast.Gt, ast.GtE)


def check_parameter_name(name: object, path: str) -> str:
    """Return ``name`` if it may name a parameter, else raise :class:`ModelDescriptionError`.

    A parameter name is an ASCII Python identifier that is not a keyword (``None``, ``class``),
    does not start with an underscore and is not reserved (:data:`RESERVED_PARAMETER_NAMES`).
    Non-ASCII names are refused because Python folds them (NFKC): the fullwidth ``ｌ`` would be
    the same identifier as ``l``.
    """
    if (
        not isinstance(name, str)
        or not name.isascii()
        or not name.isidentifier()
        or keyword.iskeyword(name)
        or name.startswith("_")
        or name in RESERVED_PARAMETER_NAMES
    ):
        raise ModelDescriptionError(
            f"{path}: invalid parameter name {name!r} (ASCII letters, digits and '_', not "
            f"starting with '_' or a digit, not a Python keyword nor one of "
            f"{sorted(RESERVED_PARAMETER_NAMES)})"
        )
    return name


def _number(node: ast.AST) -> float | None:
    """The value of a numeric literal, optionally signed; None for anything else."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        v = _number(node.operand)
        return None if v is None else (-v if isinstance(node.op, ast.USub) else v)
    if (
        isinstance(node, ast.Constant)
        and not isinstance(node.value, bool)
        and isinstance(node.value, int | float)
    ):
        return float(node.value)
    return None


def _check_ast(
    node: ast.AST, names: Mapping[str, Any] | None, path: str, depth: int = 0,
    power: float = 1.0,
) -> None:
    """Raise unless ``node`` uses only numbers, known names, + - * / **, sqrt/sin/cos.

    The tree is bounded: at most :data:`MAX_EXPRESSION_DEPTH` deep, exponents are numeric
    literals of magnitude at most :data:`MAX_EXPONENT`, integer literals at most
    :data:`MAX_INTEGER_LITERAL` (so ``9**9**9`` and huge literals are refused, not evaluated).
    Nested powers multiply their exponents: ``power`` is the product of the exponents of the
    powers ``node`` is inside the base of, and it too must stay within :data:`MAX_EXPONENT`
    (``((9**16)**16)**16`` is ``9**4096``: refused before evaluation).
    """
    if depth > MAX_EXPRESSION_DEPTH:
        raise ModelDescriptionError(
            f"{path}: expression nested deeper than {MAX_EXPRESSION_DEPTH} levels"
        )
    sub = depth + 1
    if isinstance(node, ast.Expression):
        _check_ast(node.body, names, path, sub, power)
    elif isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, int | float):
            raise ModelDescriptionError(f"{path}: only numeric constants are allowed")
        if isinstance(node.value, int) and abs(node.value) > MAX_INTEGER_LITERAL:
            raise ModelDescriptionError(f"{path}: integer literal too large")
        if not math.isfinite(float(node.value)):
            raise ModelDescriptionError(f"{path}: constants must be finite")
    elif isinstance(node, ast.Name):
        if node.id != "pi" and names is not None and node.id not in names:
            raise ModelDescriptionError(f"{path}: unknown parameter {node.id!r}")
    elif isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
        base_power = power
        if isinstance(node.op, ast.Pow):
            k = _number(node.right)
            if k is None or abs(k) > MAX_EXPONENT:
                raise ModelDescriptionError(
                    f"{path}: exponents must be numbers of magnitude <= {MAX_EXPONENT:g} "
                    "(use sqrt for square roots)"
                )
            base_power = power * max(abs(k), 1.0)
            if base_power > MAX_EXPONENT:
                raise ModelDescriptionError(
                    f"{path}: nested powers raise to a total exponent of {base_power:g} (the "
                    f"product of the nested exponents); it must be at most {MAX_EXPONENT:g}")
        _check_ast(node.left, names, path, sub, base_power)
        _check_ast(node.right, names, path, sub, power)
    elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        _check_ast(node.operand, names, path, sub, power)
    elif (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id in _FUNCS
        and len(node.args) == 1
        and not node.keywords
    ):
        _check_ast(node.args[0], names, path, sub, power)
    else:
        raise ModelDescriptionError(
            f"{path}: unsupported expression syntax ({type(node).__name__})"
        )


def _parse_expr(text: str, path: str) -> ast.Expression:
    if len(text) > MAX_EXPRESSION_LENGTH:
        raise ModelDescriptionError(
            f"{path}: expression longer than {MAX_EXPRESSION_LENGTH} characters"
        )
    try:
        tree = ast.parse(text, mode="eval")
    except (SyntaxError, RecursionError, MemoryError, ValueError) as exc:
        units = re.search(r"\d\s*(deg|rad|m|cm|mm|kg|g|s)\b", text)
        hint = (": values in a walker file are plain numbers in SI units (angles in radians), "
                f"without a unit such as {units.group(1)!r}") if units else ""
        raise ModelDescriptionError(f"{path}: invalid expression {text!r}{hint}") from exc
    return tree


def _parse_constraint(text: object, names: Mapping[str, Any], path: str) -> str:
    """Validate a constraint such as ``"R <= l"`` or ``"0 <= b < l"``; return it."""
    if not isinstance(text, str):
        raise ModelDescriptionError(f"{path}: must be a string such as 'R <= l'")
    if len(text) > MAX_EXPRESSION_LENGTH:
        raise ModelDescriptionError(
            f"{path}: constraint longer than {MAX_EXPRESSION_LENGTH} characters"
        )
    try:
        tree = ast.parse(text, mode="eval")
    except (SyntaxError, RecursionError, MemoryError, ValueError) as exc:
        raise ModelDescriptionError(f"{path}: invalid constraint {text!r}") from exc
    body = tree.body
    if not isinstance(body, ast.Compare) or not all(
        isinstance(op, _COMPARE_OPS) for op in body.ops
    ):
        raise ModelDescriptionError(
            f"{path}: a constraint compares expressions with <, <=, > or >= (e.g. 'R <= l')"
        )
    for operand in (body.left, *body.comparators):
        _check_ast(operand, names, path, 1)
    return text


def constraint_holds(text: str, values: Mapping[str, Any]) -> bool:
    """True where the (validated) constraint ``text`` holds for all entries of ``values``."""
    body = ast.parse(text, mode="eval").body
    assert isinstance(body, ast.Compare)
    sides = [
        np.asarray(evaluate_expression(ast.unparse(node), values), dtype=float)
        for node in (body.left, *body.comparators)
    ]
    ok = np.asarray(True)
    for op, a, b in zip(body.ops, sides[:-1], sides[1:], strict=True):
        if isinstance(op, ast.Lt):
            ok = ok & (a < b)
        elif isinstance(op, ast.LtE):
            ok = ok & (a <= b)
        elif isinstance(op, ast.Gt):
            ok = ok & (a > b)
        else:
            ok = ok & (a >= b)
    return bool(np.all(ok))


def evaluate_expression(
    value: Expr,
    names: Mapping[str, Any],
    *,
    funcs: Mapping[str, Callable[[Any], Any]] | None = None,
    pi: Any = math.pi,
    path: str = "<expr>",
) -> Any:
    """Evaluate a field value with the given parameter values (numeric or symbolic).

    Parameters
    ----------
    value : float or str
        A number, or an expression in the parameter names.
    names : mapping
        Parameter name -> value (floats, arrays or sympy symbols).
    funcs : mapping, optional
        Implementations of ``sqrt``, ``sin``, ``cos`` (default: numpy's).
    pi : optional
        Value of ``pi`` (e.g. ``sympy.pi`` for symbolic evaluation).
    path : str
        Field path used in error messages.
    """
    if not isinstance(value, str):
        return float(value)
    tree = _parse_expr(value, path)
    _check_ast(tree, names, path)
    fns: Mapping[str, Callable[[Any], Any]] = funcs or {
        "sqrt": np.sqrt,
        "sin": np.sin,
        "cos": np.cos,
    }

    def ev(node: ast.AST) -> Any:
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant):
            return float(node.value) if isinstance(node.value, float) else node.value
        if isinstance(node, ast.Name):
            return pi if node.id == "pi" else names[node.id]
        if isinstance(node, ast.BinOp):
            a, b = ev(node.left), ev(node.right)
            out = _BINOPS[type(node.op)](a, b)
            if isinstance(out, int) and abs(out) > MAX_INTEGER_LITERAL:
                out = float(out)  # exact integers end where floats do (OverflowError beyond)
            if isinstance(out, float) and math.isinf(out) and not (
                    (isinstance(a, float) and math.isinf(a))
                    or (isinstance(b, float) and math.isinf(b))):
                raise OverflowError(f"{ast.unparse(node)} overflows the floating-point range")
            return out
        if isinstance(node, ast.UnaryOp):
            v = ev(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        assert isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
        return fns[node.func.id](ev(node.args[0]))

    try:
        with np.errstate(invalid="ignore", divide="ignore"):  # NaN/inf: checked by the caller
            return ev(tree)
    except ArithmeticError as exc:  # 1 / 0, 0 ** -1, overflow
        raise ModelDescriptionError(f"{path}: {value!r} cannot be evaluated: {exc}") from None


# -- dataclasses --------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class JointSpec:
    """Revolute joint connecting a link to its parent.

    Attributes
    ----------
    name : str
        Coordinate name of the joint (relative angle ``theta_child - theta_parent``, rad).
    actuated : bool
        A torque acts across the joint (column ``e_j`` of the actuation matrix ``B``).
    lockable : bool
        The joint can lock (e.g. a knee hitting its stop); see
        :meth:`~heelstrike.models.builder.BuiltWalker.lock_jacobian`.
    lock_angle : float or str
        Relative angle (rad) at which the joint locks.
    """

    name: str
    actuated: bool = False
    lockable: bool = False
    lock_angle: Expr = 0.0


@dataclass(frozen=True, kw_only=True)
class LinkSpec:
    """A rigid link (see the module docstring for the geometry conventions).

    Attributes
    ----------
    name : str
        Unique name.
    parent : str or None
        Parent link; None for the root (the link carrying the stance foot).
    length : float or str
        Distance (m) from the proximal to the distal point, > 0.
    mass : float or str
        Mass (kg), >= 0: a massless link (a rod carrying a point mass) is accepted where the
        mass matrix stays positive definite
        (:meth:`~heelstrike.models.builder.BuiltWalker.check_mass_matrix`).
    com, com_offset : float or str
        Centre of mass along the link from the proximal point and forward offset (m).
    inertia : float or str
        Moment of inertia about the centre of mass (kg m^2), >= 0.
    direction : str
        ``"up"`` or ``"down"``: the distal direction is ``+e(theta)`` or ``-e(theta)``.
    attach, attach_offset : float or str or None
        Point on the parent where the joint sits (along, forward offset; m). ``attach = None``
        means the parent's distal end. Ignored for the root.
    joint : JointSpec or None
        The joint to the parent (None for the root).
    mirror : str or None
        The link this one becomes when the legs are swapped (None: itself, e.g. a torso).
    """

    name: str
    parent: str | None = None
    length: Expr
    mass: Expr
    com: Expr
    com_offset: Expr = 0.0
    inertia: Expr = 0.0
    direction: str = "up"
    attach: Expr | None = None
    attach_offset: Expr = 0.0
    joint: JointSpec | None = None
    mirror: str | None = None


@dataclass(frozen=True, kw_only=True)
class FootSpec:
    """A convex foot rigidly attached to a link: a circular arc, or any convex roll-over
    profile given by its support function.

    Attributes
    ----------
    link : str
        The link carrying the foot.
    radius : float or str or None
        Arc radius ``R`` (m), >= 0 (0: point foot); None for a profile foot.
    centre, centre_offset : float or str
        Arc centre on the link (along, forward offset; m); for a profile foot the origin
        ``O`` its support function is measured from.
    name : str
        ``"stance"`` (the foot on the root link) or ``"swing"``.
    profile : float or str or None
        Support function ``h(phi)`` (m) of a profile foot, an expression in the parameters and
        the angle ``phi`` (rad): the distance from ``O`` to the foot's tangent line whose
        outward normal is turned by ``phi`` from the link's downward axis towards its forward
        side (``"R"`` is a circle of radius ``R`` about ``O``). None for an arc foot.
    phi_range : tuple of two (float or str)
        The angles ``phi`` (rad) the profile covers, ``phi_min < 0 < phi_max``; the profile
        is checked convex there (:func:`check_profile`). Unused for an arc foot.
    """

    name: str
    link: str
    radius: Expr | None
    centre: Expr
    centre_offset: Expr = 0.0
    profile: Expr | None = None
    phi_range: tuple[Expr, Expr] = (0.0, 0.0)

    @property
    def expressions(self) -> tuple[Expr, ...]:
        """Every expression of the foot (for the parameters it uses)."""
        shape = (self.radius,) if self.profile is None else (self.profile, *self.phi_range)
        return (*(e for e in shape if e is not None), self.centre, self.centre_offset)


#: Name of the profile angle in a foot's ``profile`` expression (rad).
PROFILE_ANGLE = "phi"
#: Points of the grid over ``phi_range`` on which a profile's convexity is checked.
PROFILE_GRID = 2001


class _Jet:
    """Truncated Taylor series ``(f, f', f'')`` in one variable: exact second derivatives of
    the safe expressions (numbers, + - * / **, sqrt, sin, cos) without sympy."""

    __slots__ = ("d0", "d1", "d2")
    #: numpy defers to the jet's reflected operators (``array * jet`` is a jet of arrays, not
    #: an object array of jets: parameter values given as arrays, e.g. a complex step)
    __array_ufunc__ = None

    def __init__(self, d0: Any, d1: Any = 0.0, d2: Any = 0.0) -> None:
        self.d0, self.d1, self.d2 = d0, d1, d2

    @staticmethod
    def lift(x: Any) -> _Jet:
        return x if isinstance(x, _Jet) else _Jet(x)

    def __add__(self, o: Any) -> _Jet:
        o = _Jet.lift(o)
        return _Jet(self.d0 + o.d0, self.d1 + o.d1, self.d2 + o.d2)

    __radd__ = __add__

    def __neg__(self) -> _Jet:
        return _Jet(-self.d0, -self.d1, -self.d2)

    def __pos__(self) -> _Jet:
        return self

    def __sub__(self, o: Any) -> _Jet:
        return self + (-_Jet.lift(o))

    def __rsub__(self, o: Any) -> _Jet:
        return _Jet.lift(o) + (-self)

    def __mul__(self, o: Any) -> _Jet:
        o = _Jet.lift(o)
        return _Jet(self.d0 * o.d0, self.d1 * o.d0 + self.d0 * o.d1,
                    self.d2 * o.d0 + 2.0 * self.d1 * o.d1 + self.d0 * o.d2)

    __rmul__ = __mul__

    def _chain(self, f0: Any, f1: Any, f2: Any) -> _Jet:
        """``f(self)`` from ``f, f', f''`` at ``self.d0``."""
        return _Jet(f0, f1 * self.d1, f2 * self.d1**2 + f1 * self.d2)

    def __truediv__(self, o: Any) -> _Jet:
        return self * _Jet.lift(o) ** -1.0

    def __rtruediv__(self, o: Any) -> _Jet:
        return _Jet.lift(o) * self**-1.0

    def __pow__(self, k: Any) -> _Jet:
        k = float(k)
        if k in (0.0, 1.0):  # exact (the general rule would evaluate 0 ** -1 at x = 0)
            return self if k else _Jet(self.d0**0.0)
        x = self.d0
        return self._chain(x**k, k * x ** (k - 1.0), k * (k - 1.0) * x ** (k - 2.0))

    def sqrt(self) -> _Jet:
        return self**0.5

    def sin(self) -> _Jet:
        return self._chain(np.sin(self.d0), np.cos(self.d0), -np.sin(self.d0))

    def cos(self) -> _Jet:
        return self._chain(np.cos(self.d0), -np.sin(self.d0), -np.cos(self.d0))


_JET_FUNCS: Mapping[str, Callable[[Any], Any]] = {
    name: (lambda f: lambda x: getattr(_Jet.lift(x), f)())(name) for name in _FUNCS
}


def support_function(
    profile: Expr, phi: ArrayLike, values: Mapping[str, Any], path: str = "<profile>"
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """A profile's support function and its first two derivatives at angles ``phi``.

    Parameters
    ----------
    profile : float or str
        ``h(phi)`` (m), an expression in the parameters and ``phi``.
    phi : array_like, shape (...)
        Angles (rad); broadcast against the parameter values.
    values : mapping
        Parameter values.
    path : str
        Field path for error messages.

    Returns
    -------
    h, dh, d2h : ndarray, shape (...)
        ``h`` (m), ``h'`` (m/rad), ``h''`` (m/rad^2), exact (forward-mode differentiation of
        the expression), broadcast to the shape of ``phi`` and the values.
    """
    x = _Jet(np.asarray(phi, dtype=float), 1.0, 0.0)
    out = _Jet.lift(evaluate_expression(profile, {**values, PROFILE_ANGLE: x},
                                        funcs=_JET_FUNCS, path=path))
    shape = np.broadcast_shapes(*(np.shape(d) for d in (x.d0, out.d0, out.d1, out.d2)))
    # complex parameter values (complex-step derivatives) keep their imaginary parts
    h, dh, d2h = (np.broadcast_to(np.asarray(d, dtype=complex if np.iscomplexobj(d) else float),
                                  shape) for d in (out.d0, out.d1, out.d2))
    return h, dh, d2h


def rolling_radius(foot: FootSpec, values: Mapping[str, Any]) -> Any:
    """The foot's rolling radius ``R0`` (m): its arc radius, or for a profile foot its radius
    of curvature at ``phi = 0``, ``h(0) + h''(0)`` (the contact point with the link upright).

    The walker's coordinates ``(x, y)`` are those of a disc of this radius rolling with the
    stance foot (``y = R0``, ``x_dot = -R0 theta_dot``): the arc centre for an arc foot
    (``docs/walker_files.rst``, "Feet of any convex shape").
    """
    if foot.profile is None:
        assert foot.radius is not None
        return evaluate_expression(foot.radius, values)
    h, _, d2h = support_function(foot.profile, 0.0, values)
    # arrays (a batch) and complex values (complex-step derivatives) stay as they are
    return h + d2h if np.ndim(h) or np.iscomplexobj(h) else float(h + d2h)


def check_profile(foot: FootSpec, values: Mapping[str, Any], path: str) -> None:
    """Refuse a profile foot that is not convex or that overlaps itself.

    On :data:`PROFILE_GRID` angles over ``phi_range`` (at the given parameter values) the
    radius of curvature ``rho = h + h''`` must be ``>= 0`` (a convex contact curve; where it
    is negative the curve ``p = h n + h' t`` turns back through a cusp), and the range must
    span less than a full turn (a curve with ``rho >= 0`` turning by ``2 pi`` or more is
    closed or wraps over itself: self-intersecting). It must also contain ``phi = 0`` (the
    contact with the link upright).

    Raises
    ------
    ModelDescriptionError
        ``foot[i].profile: not convex ...`` or ``foot[i].phi_range: ...``.
    """
    assert foot.profile is not None
    lo, hi = (np.asarray(evaluate_expression(v, values, path=f"{path}.phi_range"), dtype=float)
              for v in foot.phi_range)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise ModelDescriptionError(f"{path}.phi_range: must be finite")
    if not np.all((lo < 0.0) & (0.0 < hi)):
        raise ModelDescriptionError(
            f"{path}.phi_range: must be [phi_min, phi_max] with phi_min < 0 < phi_max (rad), "
            f"got [{_show(lo)}, {_show(hi)}]: the profile must contain the contact with the "
            "link upright (phi = 0)")
    if not np.all(hi - lo < 2.0 * np.pi):
        raise ModelDescriptionError(
            f"{path}.phi_range: the profile turns through {float(np.max(hi - lo)):g} rad, a "
            "full turn (2 pi) or more, so its contact curve closes on or overlaps itself "
            "(self-intersecting); give a range shorter than 2 pi")
    nd = max([np.ndim(v) for v in values.values()] + [lo.ndim, hi.ndim])
    s = np.linspace(0.0, 1.0, PROFILE_GRID).reshape((-1,) + (1,) * nd)
    phi = lo + (hi - lo) * s
    h, _, d2h = support_function(foot.profile, phi, values, path=f"{path}.profile")
    rho = h + d2h
    if not np.all(np.isfinite(rho)):
        raise ModelDescriptionError(
            f"{path}.profile: must be finite (with its first two derivatives) over phi_range")
    tol = 1e-12 * max(float(np.max(np.abs(h))), float(np.max(np.abs(d2h))), 1.0)
    if np.any(rho < -tol):
        k = np.unravel_index(int(np.argmin(rho)), rho.shape)
        phi_k = np.broadcast_to(phi, rho.shape)[k]
        raise ModelDescriptionError(
            f"{path}.profile: not convex: its radius of curvature h + h'' is "
            f"{float(rho[k]):.6g} m < 0 at phi = {float(phi_k):.6g} rad (a convex foot has "
            "h + h'' >= 0 over phi_range; where it is negative the contact curve turns back "
            "through a cusp and crosses itself)")


@dataclass(frozen=True, kw_only=True)
class PointMassSpec:
    """A point mass rigidly attached to a link (e.g. the hip mass ``mH``).

    Attributes
    ----------
    name : str
        Unique name.
    link : str
        The carrying link.
    at, offset : float or str
        Position on the link (along, forward offset; m).
    mass : float or str
        Mass (kg), > 0.
    """

    name: str
    link: str
    at: Expr
    offset: Expr = 0.0
    mass: Expr


@dataclass(frozen=True, kw_only=True)
class PostureLawSpec:
    """A declared PD posture law (``[control.<name>]``): the torque across ``joint``

    .. math:: u = -k_p (\\theta - \\theta_{ref}) - k_d \\dot\\theta,

    with ``theta`` the absolute angle of the joint's child link (rad, from the ground normal);
    the reaction acts on the root (stance) link. Simulated by
    :class:`heelstrike.dynamics.phased.TorsoPD`.

    Attributes
    ----------
    name : str
        Table key (e.g. ``"torso"``).
    joint : str
        An actuated joint whose parent link is the root.
    kp : float or str
        Stiffness (N m/rad), >= 0.
    kd : float or str
        Damping (N m s/rad), >= 0.
    angle : float or str
        Set point ``theta_ref`` (rad).
    """

    name: str
    joint: str
    kp: Expr
    kd: Expr
    angle: Expr = 0.0


@dataclass(frozen=True, kw_only=True)
class PoweredSpec:
    """The walker's declared default target for a powered gait (the ``[powered]`` table).

    Attributes
    ----------
    speed : float
        Target mean speed (m/s), finite and > 0: the level-ground gait ``heelstrike powered``
        seeks when given neither ``--speed`` nor ``--step-length``
        (:attr:`heelstrike.models.base.PlanarWalker.powered_speed`).
    """

    speed: float


#: The heel strike's resets a walker file may declare (``[events] reset``): the striking foot
#: becomes the stance foot, every link swapped with its mirror (the only one so far).
EVENT_RESETS = ("swap_legs",)
#: What the trailing foot may do at a declared heel strike (``[events] trailing_foot``).
TRAILING_FOOT_RULES = ("lifts", "lifts_or_grazes")


@dataclass(frozen=True, kw_only=True)
class EventsSpec:
    """The walker's declared heel-strike witness and reset (the ``[events]`` table).

    Drake's idea that a model declares its own events: the guard is an expression in the
    walker's coordinates (:attr:`WalkerDescription.coordinate_names`) and parameters, and the
    heel strike happens when it rises through zero once the stance leg has passed the vertical
    (with the swing foot touching the ground);
    :meth:`heelstrike.models.builder.BuiltWalker.step_schedule` runs it instead of the swing
    foot's clearance.

    Attributes
    ----------
    heel_strike : str
        The guard ``g(q)`` (units of what it measures; e.g. ``"2 * stance_leg + hip"``, the
        symmetric configuration of a compass gait, rad). Just after the heel strike, the legs
        relabelled, it is zero too: it also places the hip on the Poincare section
        (:class:`heelstrike.dynamics.phased.PhasedWalker`).
    reset : str
        ``"swap_legs"`` (:data:`EVENT_RESETS`): the striking (swing) foot becomes the stance
        foot and every link is relabelled as its mirror.
    trailing_foot : str
        ``"lifts"`` (the default, the described walkers' rule: the trailing foot is a
        candidate contact of the impact and must separate and lift) or ``"lifts_or_grazes"``
        (the paper's projector with the striking foot's rows, eq. 13; the trailing foot may
        also leave with zero normal velocity to round-off, as it does when both feet are arcs
        of one circle: McGeer's wheel).
    """

    heel_strike: str
    reset: str = "swap_legs"
    trailing_foot: str = "lifts"


@dataclass(frozen=True, kw_only=True)
class WalkerDescription:
    """A validated walker description.

    Attributes
    ----------
    name : str
        Model name.
    params : tuple of (str, float)
        Default parameter values, sorted by name; always contains ``g`` (m/s^2).
    links : tuple of LinkSpec
        Links in tree order (root first, parents before children).
    feet : tuple of FootSpec
        ``(stance, swing)``.
    point_masses : tuple of PointMassSpec
        Extra point masses.
    constraints : tuple of str
        Conditions on the parameter values that the model needs to make physical sense, e.g.
        ``"R <= l"`` (comparisons ``< <= > >=`` of expressions, chains allowed); checked by
        :meth:`check_values` whenever values are set.
    control : tuple of PostureLawSpec
        Declared posture laws (``[control.<name>]`` tables); not part of the derivation.
    powered : PoweredSpec or None
        The declared default powered target (``[powered]``), or None; not part of the
        derivation.
    events : EventsSpec or None
        The declared heel-strike guard and reset (``[events]``), or None: the swing foot's
        clearance and the default reset.
    swap : tuple of (str, str)
        The ``[swap]`` table of a walker whose legs differ: pairs ``(k, j)``, sorted, meaning
        that after the leg swap parameter ``k`` takes the value ``j`` had (the stance leg's
        parameters become the swing leg's and back; an involution, listed both ways). Empty
        when the leg swap is a symmetry of the walker as written. Not part of the derivation.
    source : str
        Where the description came from (file path or ``"<dict>"``); not part of the model.
    """

    name: str
    params: tuple[tuple[str, float], ...]
    links: tuple[LinkSpec, ...]
    feet: tuple[FootSpec, FootSpec]
    point_masses: tuple[PointMassSpec, ...] = ()
    constraints: tuple[str, ...] = ()
    control: tuple[PostureLawSpec, ...] = ()
    powered: PoweredSpec | None = None
    events: EventsSpec | None = None
    swap: tuple[tuple[str, str], ...] = ()
    source: str = field(default="<dict>", compare=False)

    @property
    def param_names(self) -> tuple[str, ...]:
        """Parameter names in the order the generated functions take them."""
        return tuple(k for k, _ in self.params)

    @property
    def default_params(self) -> dict[str, float]:
        """Default parameter values."""
        return dict(self.params)

    @functools.cached_property
    def unused_params(self) -> frozenset[str]:
        """Parameters declared in ``[params]`` that no field, foot, point mass or posture law
        uses (``g`` is always used): their values change nothing. Constraints do not count.
        Computed once per description (every walker built from it asks)."""
        exprs: list[Any] = []
        for lk in self.links:
            exprs += [lk.length, lk.mass, lk.com, lk.com_offset, lk.inertia, lk.attach,
                      lk.attach_offset, lk.joint.lock_angle if lk.joint is not None else None]
        for ft in self.feet:
            exprs += list(ft.expressions)
        for pm in self.point_masses:
            exprs += [pm.at, pm.offset, pm.mass]
        for law in self.control:
            exprs += [law.kp, law.kd, law.angle]
        if self.events is not None:
            exprs.append(self.events.heel_strike)
        used = {"g"}
        for e in exprs:
            if isinstance(e, str):
                used |= {n.id for n in ast.walk(ast.parse(e, mode="eval"))
                         if isinstance(n, ast.Name)}
        return frozenset(self.param_names) - used

    @property
    def root(self) -> LinkSpec:
        """The root link (carries the stance foot)."""
        return self.links[0]

    def link(self, name: str) -> LinkSpec:
        """The link called ``name``."""
        for lk in self.links:
            if lk.name == name:
                return lk
        raise KeyError(name)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        """``("x", "y", <root link name>, <joint names in tree order>)``."""
        joints = tuple(lk.joint.name for lk in self.links[1:] if lk.joint is not None)
        return ("x", "y", self.root.name, *joints)

    @property
    def point_names(self) -> tuple[str, ...]:
        """Names of the points the generated ``points`` function returns, in its order.

        Each link's ``.proximal``, ``.distal``, ``.com`` (tree order), the point masses, then
        ``stance_foot.centre``, ``stance_foot.contact``, ``swing_foot.centre``,
        ``swing_foot.contact``.
        """
        names: list[str] = []
        for lk in self.links:
            names += [f"{lk.name}.proximal", f"{lk.name}.distal", f"{lk.name}.com"]
        names += [pm.name for pm in self.point_masses]
        for ft in self.feet:
            names += [f"{ft.name}_foot.centre", f"{ft.name}_foot.contact"]
        return tuple(names)

    def structure_key(self) -> str:
        """Canonical JSON of everything the derivation depends on (not parameter values)."""
        d = asdict(self)
        d.pop("source")
        d.pop("constraints")
        d.pop("control")
        d.pop("powered")
        if self.events is None:  # the structure of walkers without [events] as before
            d.pop("events")
        d.pop("swap")
        d["params"] = [k for k, _ in self.params]
        for ft in d["feet"]:
            if ft["profile"] is None:  # an arc foot: the key it had before profiles existed
                del ft["profile"], ft["phi_range"]
        return json.dumps(d, sort_keys=True, default=str)

    def check_values(self, values: Mapping[str, Any]) -> None:
        """Check the physical signs of all fields for the given parameter values.

        Raises
        ------
        ModelDescriptionError
            E.g. ``link[2].mass: must be > 0`` (indices in tree order).
        """

        def ev(v: Expr, path: str) -> Any:
            out = np.asarray(evaluate_expression(v, values, path=path), dtype=float)
            if not np.all(np.isfinite(out)):
                raise ModelDescriptionError(f"{path}: must be finite")
            _bounded(out, path)
            return out

        for k, v in values.items():
            if not np.all(np.isfinite(np.asarray(v, dtype=float))):
                raise ModelDescriptionError(f"params.{k}: must be finite")
            _bounded(np.asarray(v, dtype=float), f"params.{k}")
        if not np.all(np.asarray(values["g"], dtype=float) > 0):
            raise ModelDescriptionError("params.g: must be > 0")
        for i, lk in enumerate(self.links):
            p = f"link[{i}]"
            if not np.all(ev(lk.mass, f"{p}.mass") >= 0):
                raise ModelDescriptionError(
                    f"{p}.mass: must be > 0, or 0 for a massless link (a rod carrying a point "
                    "mass)")
            if not np.all(ev(lk.length, f"{p}.length") > 0):
                raise ModelDescriptionError(f"{p}.length: must be > 0")
            if not np.all(ev(lk.inertia, f"{p}.inertia") >= 0):
                raise ModelDescriptionError(f"{p}.inertia: must be >= 0")
            ev(lk.com, f"{p}.com")
            ev(lk.com_offset, f"{p}.com_offset")
            if lk.attach is not None:
                ev(lk.attach, f"{p}.attach")
            ev(lk.attach_offset, f"{p}.attach_offset")
            if lk.joint is not None:
                ev(lk.joint.lock_angle, f"{p}.joint.lock_angle")
        for i, ft in enumerate(self.feet):
            p = f"foot[{i}]"
            if ft.profile is not None:
                check_profile(ft, values, p)
            elif not np.all(ev(ft.radius, f"{p}.radius") >= 0):  # type: ignore[arg-type]
                raise ModelDescriptionError(f"{p}.radius: must be >= 0")
            ev(ft.centre, f"{p}.centre")
            ev(ft.centre_offset, f"{p}.centre_offset")
        for i, pm in enumerate(self.point_masses):
            p = f"point_mass[{i}]"
            if not np.all(ev(pm.mass, f"{p}.mass") > 0):
                raise ModelDescriptionError(f"{p}.mass: must be > 0")
            ev(pm.at, f"{p}.at")
            ev(pm.offset, f"{p}.offset")
        for law in self.control:
            p = f"control.{law.name}"
            for key in ("kp", "kd"):
                if not np.all(ev(getattr(law, key), f"{p}.{key}") >= 0):
                    raise ModelDescriptionError(f"{p}.{key}: must be >= 0")
            ev(law.angle, f"{p}.angle")
        for i, text in enumerate(self.constraints):
            if not constraint_holds(text, values):
                tree = ast.parse(text, mode="eval")
                names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
                used = sorted(names & set(values))
                shown = ", ".join(f"{k}={_show(values[k])}" for k in used)
                raise ModelDescriptionError(
                    f"constraints[{i}]: {text!r} is violated ({shown})"
                )


def _bounded(values: Any, path: str) -> None:
    """Refuse values of magnitude beyond :data:`MAX_FIELD_MAGNITUDE` (SI units)."""
    big = np.abs(np.asarray(values, dtype=float))
    if big.size and float(big.max()) > MAX_FIELD_MAGNITUDE:
        raise ModelDescriptionError(
            f"{path}: {float(big.max()):g} is beyond the magnitude {MAX_FIELD_MAGNITUDE:g} "
            "heelstrike accepts (SI units: kg, m, kg m^2, rad; larger values leave the "
            "floating-point range of the walker's energies)")


def _show(v: Any) -> str:
    a = np.asarray(v, dtype=float)
    return f"{float(a):g}" if a.ndim == 0 else f"array of shape {a.shape}"


# -- units ----------------------------------------------------------------------------------------


def _names(expr: Any) -> set[str] | None:
    """Parameter names of an additive expression (``"l - b"``); None for products of names."""
    if not isinstance(expr, str):
        return set()
    try:
        tree = ast.parse(expr, mode="eval")
    except SyntaxError:
        return None
    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult | ast.Div | ast.Pow):
            if all(any(isinstance(n, ast.Name) for n in ast.walk(side))
                   for side in (node.left, node.right)):
                return None  # e.g. "m * l": no single unit per name
        if isinstance(node, ast.Call):
            return None
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and n.id != "pi"}


def parameter_units(description: WalkerDescription) -> dict[str, str]:
    """SI unit of every description parameter, read from where the parameter is used.

    Lengths, positions and foot radii are ``m``, masses ``kg``, inertias ``kg m^2``, lock angles
    ``rad`` and ``g`` ``m/s^2``. A parameter used with two different units, or only inside
    products of parameters, gets no entry.

    Parameters
    ----------
    description : WalkerDescription

    Returns
    -------
    dict of str to str
        Parameter name to unit.
    """
    uses: list[tuple[Any, str]] = []
    for lk in description.links:
        uses += [(lk.length, "m"), (lk.com, "m"), (lk.com_offset, "m"),
                 (lk.attach_offset, "m"), (lk.mass, "kg"), (lk.inertia, "kg m^2")]
        if lk.attach is not None:
            uses.append((lk.attach, "m"))
        if lk.joint is not None:
            uses.append((lk.joint.lock_angle, "rad"))
    for ft in description.feet:
        uses += [(ft.radius, "m"), (ft.centre, "m"), (ft.centre_offset, "m"),
                 (ft.profile, "m"), *((a, "rad") for a in ft.phi_range)]
    for pm in description.point_masses:
        uses += [(pm.at, "m"), (pm.offset, "m"), (pm.mass, "kg")]
    found: dict[str, set[str]] = {"g": {"m/s^2"}}
    for expr, unit in uses:
        for name in _names(expr) or ():
            found.setdefault(name, set()).add(unit)
    return {k: next(iter(v)) for k, v in found.items() if len(v) == 1}



# -- parsing ------------------------------------------------------------------------------------

_LINK_KEYS = {
    "name",
    "parent",
    "length",
    "mass",
    "com",
    "com_offset",
    "inertia",
    "direction",
    "attach",
    "attach_offset",
    "joint",
    "mirror",
}
_LINK_REQUIRED = ("name", "length", "mass", "com")
_JOINT_KEYS = {"name", "actuated", "lockable", "lock_angle"}
_FOOT_KEYS = {"name", "link", "radius", "centre", "centre_offset", "profile", "phi_range"}
_FOOT_REQUIRED = ("link",)
_PM_KEYS = {"name", "link", "at", "offset", "mass"}
_PM_REQUIRED = ("link", "at", "mass")
_TOP_KEYS = {
    "name",
    "params",
    "link",
    "foot",
    "point_mass",
    "constraints",
    "description",
    "reference",
    "control",
    "powered",
    "events",
    "swap",
}
_EVENTS_KEYS = {"heel_strike", "reset", "trailing_foot"}
_EVENTS_REQUIRED = ("heel_strike",)
_POWERED_KEYS = {"speed"}
_POWERED_REQUIRED = ("speed",)
_CONTROL_KEYS = {"joint", "kp", "kd", "angle"}
_CONTROL_REQUIRED = ("joint", "kp", "kd")


def _table(obj: Any, path: str) -> dict[str, Any]:
    if not isinstance(obj, Mapping):
        raise ModelDescriptionError(f"{path}: must be a table")
    return dict(obj)


def _check_keys(
    tab: Mapping[str, Any], allowed: set[str], required: tuple[str, ...], path: str
) -> None:
    for k in tab:
        if k not in allowed:
            raise ModelDescriptionError(f"{path}.{k}: unknown key (allowed: {sorted(allowed)})")
    for k in required:
        if k not in tab:
            raise ModelDescriptionError(f"{path}.{k}: missing required field")


def _expr(tab: Mapping[str, Any], key: str, params: Mapping[str, float], path: str) -> Expr:
    v = tab[key]
    p = f"{path}.{key}"
    if isinstance(v, bool) or not isinstance(v, int | float | str):
        raise ModelDescriptionError(f"{p}: must be a number or an expression string")
    if isinstance(v, str):
        _check_ast(_parse_expr(v, p), params, p)
        return v
    if not math.isfinite(v):
        raise ModelDescriptionError(f"{p}: must be finite")
    return float(v)


def _str(tab: Mapping[str, Any], key: str, path: str) -> str:
    v = tab[key]
    if not isinstance(v, str) or not v:
        raise ModelDescriptionError(f"{path}.{key}: must be a non-empty string")
    return v


def _bool(tab: Mapping[str, Any], key: str, path: str) -> bool:
    v = tab.get(key, False)
    if not isinstance(v, bool):
        raise ModelDescriptionError(f"{path}.{key}: must be true or false")
    return v


def parse_description(data: Mapping[str, Any], *, source: str = "<dict>") -> WalkerDescription:
    """Validate a description given as nested mappings (the parsed TOML) and build it.

    Parameters
    ----------
    data : mapping
        Top-level keys ``name``, ``params``, ``link`` (list), ``foot`` (list of two) and
        optionally ``point_mass`` (list), ``constraints``, ``control`` (declared posture laws,
        :class:`PostureLawSpec`), ``powered`` (the default powered target,
        :class:`PoweredSpec`), ``events`` (the heel-strike guard and reset,
        :class:`EventsSpec`), ``swap`` (the parameters the leg swap exchanges, for a walker
        whose legs differ), ``description``, ``reference`` (free text).
    source : str
        Origin, for messages.

    Raises
    ------
    ModelDescriptionError
        With a message ``<path>: <problem>``, e.g. ``link[2].mass: must be > 0`` (indices as
        written in the input).
    """
    top = _table(data, "<top>")
    for k in top:
        if k not in _TOP_KEYS:
            raise ModelDescriptionError(f"{k}: unknown key (allowed: {sorted(_TOP_KEYS)})")
    name = top.get("name", Path(source).stem if source != "<dict>" else "walker")
    if not isinstance(name, str) or not name.isprintable() or not 0 < len(name) <= 100:
        raise ModelDescriptionError("name: must be a printable string of 1 to 100 characters")
    raw_params = _table(top.get("params", {}), "params")
    params: dict[str, float] = {}
    for k, v in raw_params.items():
        check_parameter_name(k, f"params.{k}")
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ModelDescriptionError(f"params.{k}: must be a finite number")
        params[k] = float(v)
    params.setdefault("g", 9.81)

    raw_links = top.get("link")
    if not isinstance(raw_links, list) or not raw_links:
        raise ModelDescriptionError("link: at least one [[link]] table is required")
    if len(raw_links) > MAX_LINKS:
        raise ModelDescriptionError(
            f"link: at most {MAX_LINKS} links are supported, found {len(raw_links)}"
        )
    links: list[LinkSpec] = []
    for i, raw in enumerate(raw_links):
        p = f"link[{i}]"
        tab = _table(raw, p)
        _check_keys(tab, _LINK_KEYS, _LINK_REQUIRED, p)
        kw: dict[str, Any] = {"name": _str(tab, "name", p)}
        for key in ("parent", "mirror"):
            if key in tab:
                kw[key] = _str(tab, key, p)
        for key in ("length", "mass", "com", "com_offset", "inertia", "attach", "attach_offset"):
            if key in tab:
                kw[key] = _expr(tab, key, params, p)
        is_root = "parent" not in tab
        direction = tab.get("direction", "up" if is_root else "down")
        if direction not in ("up", "down"):
            raise ModelDescriptionError(f"{p}.direction: must be 'up' or 'down'")
        kw["direction"] = direction
        if "joint" in tab:
            if is_root:
                raise ModelDescriptionError(f"{p}.joint: the root link has no joint")
            jt = _table(tab["joint"], f"{p}.joint")
            _check_keys(jt, _JOINT_KEYS, (), f"{p}.joint")
            kw["joint"] = JointSpec(
                name=_str(jt, "name", f"{p}.joint") if "name" in jt else kw["name"],
                actuated=_bool(jt, "actuated", f"{p}.joint"),
                lockable=_bool(jt, "lockable", f"{p}.joint"),
                lock_angle=_expr(jt, "lock_angle", params, f"{p}.joint")
                if "lock_angle" in jt
                else 0.0,
            )
        elif not is_root:
            kw["joint"] = JointSpec(name=kw["name"])
        links.append(LinkSpec(**kw))

    # names, parents, cycles, single root
    index = {}
    for i, lk in enumerate(links):
        if lk.name in index:
            raise ModelDescriptionError(f"link[{i}].name: duplicate link name {lk.name!r}")
        index[lk.name] = i
    roots = [i for i, lk in enumerate(links) if lk.parent is None]
    for i, lk in enumerate(links):
        if lk.parent is not None and lk.parent not in index:
            raise ModelDescriptionError(f"link[{i}].parent: unknown link {lk.parent!r}")
    for i, lk in enumerate(links):
        seen = [lk.name]
        cur = lk
        while cur.parent is not None:
            cur = links[index[cur.parent]]
            if cur.name in seen:
                loop = " -> ".join([*seen[seen.index(cur.name) :], cur.name])
                raise ModelDescriptionError(f"link[{i}].parent: cycle {loop}")
            seen.append(cur.name)
    if len(roots) != 1:
        raise ModelDescriptionError(
            f"link: exactly one root link (without parent) is required, found {len(roots)}"
        )
    joint_names = [lk.joint.name for lk in links if lk.joint is not None]
    for i, lk in enumerate(links):
        if lk.joint is not None and (
            joint_names.count(lk.joint.name) > 1
            or lk.joint.name in ("x", "y", links[roots[0]].name)
        ):
            clash = lk.joint.name
            what = ("is a base coordinate's name (x, y)" if clash in ("x", "y") else
                    "is the root link's name (its angle's coordinate)"
                    if clash == links[roots[0]].name else "names another joint too")
            raise ModelDescriptionError(
                f"link[{i}].joint.name: duplicate coordinate name {clash!r}: it {what}")
    # tree order: root first, then repeatedly the first (file order) link whose parent is placed
    order = [roots[0]]
    placed = {links[roots[0]].name}
    while len(order) < len(links):
        for i, lk in enumerate(links):
            if i not in order and lk.parent in placed:
                order.append(i)
                placed.add(lk.name)
                break

    # mirrors
    for i, lk in enumerate(links):
        if lk.mirror is None:
            continue
        if lk.mirror not in index:
            raise ModelDescriptionError(f"link[{i}].mirror: unknown link {lk.mirror!r}")
        other = links[index[lk.mirror]]
        if other.mirror != lk.name and not (other.mirror is None and other.name == lk.name):
            raise ModelDescriptionError(
                f"link[{i}].mirror: {lk.mirror!r} must mirror {lk.name!r} back"
            )

    # feet
    raw_feet = top.get("foot")
    if not isinstance(raw_feet, list) or len(raw_feet) != 2:
        n = len(raw_feet) if isinstance(raw_feet, list) else 0
        raise ModelDescriptionError(f"foot: exactly two [[foot]] tables are required, found {n}")
    feet_by_role: dict[str, FootSpec] = {}
    for i, raw in enumerate(raw_feet):
        p = f"foot[{i}]"
        tab = _table(raw, p)
        _check_keys(tab, _FOOT_KEYS, _FOOT_REQUIRED, p)
        link_name = _str(tab, "link", p)
        if link_name not in index:
            raise ModelDescriptionError(f"{p}.link: unknown link {link_name!r}")
        role = "stance" if link_name == links[roots[0]].name else "swing"
        if "name" in tab and tab["name"] != role:
            raise ModelDescriptionError(
                f"{p}.name: must be {role!r} (the stance foot is the one on the root link)"
            )
        if role in feet_by_role:
            raise ModelDescriptionError(
                f"{p}.link: exactly one foot must be on the root link {links[roots[0]].name!r}"
            )
        lk = links[index[link_name]]
        profile: Expr | None = None
        phi_range: tuple[Expr, Expr] = (0.0, 0.0)
        radius: Expr | None = None
        if "profile" in tab:
            if "radius" in tab:
                raise ModelDescriptionError(
                    f"{p}.radius: a foot is either an arc (radius) or a profile, not both")
            if PROFILE_ANGLE in params:
                raise ModelDescriptionError(
                    f"params.{PROFILE_ANGLE}: {PROFILE_ANGLE!r} is the angle of a foot "
                    "profile; rename the parameter")
            profile = _expr(tab, "profile", {**params, PROFILE_ANGLE: 0.0}, p)
            if "phi_range" not in tab:
                raise ModelDescriptionError(
                    f"{p}.phi_range: missing required field (a profile foot gives the angles "
                    "[phi_min, phi_max] (rad) it covers)")
            raw_range = tab["phi_range"]
            if not isinstance(raw_range, list) or len(raw_range) != 2:
                raise ModelDescriptionError(
                    f"{p}.phi_range: must be a pair [phi_min, phi_max] (rad)")
            pr = {"lo": raw_range[0], "hi": raw_range[1]}
            phi_range = (_expr(pr, "lo", params, f"{p}.phi_range"),
                         _expr(pr, "hi", params, f"{p}.phi_range"))
            if "centre" in tab:
                centre: Expr = _expr(tab, "centre", params, p)
            else:  # the link's foot end
                centre = 0.0 if role == "stance" else lk.length
        elif "radius" not in tab:
            raise ModelDescriptionError(
                f"{p}.radius: missing required field (or give a profile)")
        else:
            if "phi_range" in tab:
                raise ModelDescriptionError(
                    f"{p}.phi_range: only a profile foot has one (this foot is an arc)")
            radius = _expr(tab, "radius", params, p)
            if "centre" in tab:
                centre = _expr(tab, "centre", params, p)
            elif role == "stance":
                centre = radius
            else:
                centre = f"({lk.length}) - ({radius})"
        feet_by_role[role] = FootSpec(
            name=role,
            link=link_name,
            radius=radius,
            centre=centre,
            centre_offset=_expr(tab, "centre_offset", params, p) if "centre_offset" in tab else 0.0,
            profile=profile,
            phi_range=phi_range,
        )
    if "stance" not in feet_by_role:
        raise ModelDescriptionError(
            f"foot: one foot must be on the root link {links[roots[0]].name!r}"
        )
    swing_link = feet_by_role["swing"].link
    root_mirror = links[roots[0]].mirror
    if root_mirror is not None and root_mirror != swing_link:
        raise ModelDescriptionError(
            f"link[{roots[0]}].mirror: the root must mirror the swing foot's link {swing_link!r}"
        )

    # point masses
    raw_pm = top.get("point_mass", [])
    if not isinstance(raw_pm, list):
        raise ModelDescriptionError("point_mass: must be an array of tables")
    pms: list[PointMassSpec] = []
    for i, raw in enumerate(raw_pm):
        p = f"point_mass[{i}]"
        tab = _table(raw, p)
        _check_keys(tab, _PM_KEYS, _PM_REQUIRED, p)
        link_name = _str(tab, "link", p)
        if link_name not in index:
            raise ModelDescriptionError(f"{p}.link: unknown link {link_name!r}")
        pms.append(
            PointMassSpec(
                name=_str(tab, "name", p) if "name" in tab else f"point_mass_{i}",
                link=link_name,
                at=_expr(tab, "at", params, p),
                offset=_expr(tab, "offset", params, p) if "offset" in tab else 0.0,
                mass=_expr(tab, "mass", params, p),
            )
        )

    raw_constraints = top.get("constraints", [])
    if not isinstance(raw_constraints, list):
        raise ModelDescriptionError("constraints: must be an array of strings such as 'R <= l'")
    constraints = tuple(
        _parse_constraint(c, params, f"constraints[{i}]") for i, c in enumerate(raw_constraints)
    )

    control = _parse_control(top.get("control", {}), params, links, roots[0])
    powered = _parse_powered(top["powered"]) if "powered" in top else None
    desc = WalkerDescription(
        name=name,
        params=tuple(sorted(params.items())),
        links=tuple(links[i] for i in order),
        feet=(feet_by_role["stance"], feet_by_role["swing"]),
        point_masses=tuple(pms),
        constraints=constraints,
        control=control,
        powered=powered,
        source=source,
    )
    desc = replace(desc, swap=_parse_swap(top.get("swap", {}), params, desc))
    if "events" in top:
        desc = replace(desc, events=_parse_events(top["events"], params, desc))
    seen_points: set[str] = set()
    for point_name in desc.point_names:
        if point_name in seen_points:
            raise ModelDescriptionError(
                f"point_mass: name {point_name!r} is used twice (point masses must not share "
                "a name with each other or with a link's '.proximal', '.distal', '.com')"
            )
        seen_points.add(point_name)
    try:
        desc.check_values(desc.default_params)
    except ModelDescriptionError as exc:
        # report link indices as written in the input, not in tree order
        msg = str(exc)
        if msg.startswith("link["):
            k_tree = int(msg[5 : msg.index("]")])
            msg = f"link[{order[k_tree]}]" + msg[msg.index("]") + 1 :]
        raise ModelDescriptionError(msg) from None
    return desc


def _parse_control(
    raw: Any, params: Mapping[str, float], links: list[LinkSpec], root: int
) -> tuple[PostureLawSpec, ...]:
    """Validate the optional ``[control.<name>]`` tables (declared posture laws)."""
    tab = _table(raw, "control")
    out: list[PostureLawSpec] = []
    joints = {lk.joint.name: lk for lk in links if lk.joint is not None}
    used: set[str] = set()
    for key, value in tab.items():
        p = f"control.{key}"
        if not isinstance(key, str) or not key.isascii() or not key.isidentifier():
            raise ModelDescriptionError(f"{p}: the law's name must be an ASCII identifier")
        law = _table(value, p)
        _check_keys(law, _CONTROL_KEYS, _CONTROL_REQUIRED, p)
        joint = _str(law, "joint", p)
        lk = joints.get(joint)
        if lk is None or lk.joint is None or not lk.joint.actuated:
            raise ModelDescriptionError(
                f"{p}.joint: {joint!r} is not an actuated joint (actuated joints: "
                f"{sorted(j for j, k in joints.items() if k.joint and k.joint.actuated)})"
            )
        if lk.parent != links[root].name:
            raise ModelDescriptionError(
                f"{p}.joint: {joint!r} must connect a link to the root link "
                f"{links[root].name!r} (the law's reaction acts on the stance link)"
            )
        if joint in used:
            raise ModelDescriptionError(f"{p}.joint: {joint!r} already has a posture law")
        if joint != "torso" or used:  # what TorsoPD and the compiled kernel drive
            raise ModelDescriptionError(
                f"{p}.joint: one posture law, on a joint named 'torso', is supported "
                f"(got {joint!r}{' as a second law' if used else ''})")
        used.add(joint)
        out.append(
            PostureLawSpec(
                name=key,
                joint=joint,
                kp=_expr(law, "kp", params, p),
                kd=_expr(law, "kd", params, p),
                angle=_expr(law, "angle", params, p) if "angle" in law else 0.0,
            )
        )
    return tuple(out)


def _parse_events(
    raw: Any, params: Mapping[str, float], desc: WalkerDescription
) -> EventsSpec:
    """Validate the optional ``[events]`` table (the declared heel-strike guard and reset)."""
    tab = _table(raw, "events")
    _check_keys(tab, _EVENTS_KEYS, _EVENTS_REQUIRED, "events")
    p = "events.heel_strike"
    guard = tab["heel_strike"]
    coords = desc.coordinate_names
    if not isinstance(guard, str) or not guard.strip():
        raise ModelDescriptionError(
            f"{p}: must be an expression string in the coordinates {list(coords)} and the "
            "parameters (e.g. '2 * stance_leg + hip'); a number cannot cross zero")
    tree = _parse_expr(guard, p)
    used = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and n.id != "pi"}
    unknown = sorted(used - set(coords) - set(params) - set(_FUNCS))
    if unknown:
        raise ModelDescriptionError(
            f"{p}: unknown name {unknown[0]!r} (coordinates: {list(coords)}; parameters: "
            f"{sorted(params)})")
    both = sorted(used & set(coords) & set(params))
    if both:
        raise ModelDescriptionError(
            f"{p}: {both[0]!r} names both a coordinate and a parameter: rename the parameter")
    _check_ast(tree, {**params, **dict.fromkeys(coords, 0.0)}, p)
    if not used & set(coords):
        raise ModelDescriptionError(
            f"{p}: {guard!r} does not depend on the state: a guard is an expression in the "
            f"coordinates {list(coords)} (and the parameters) that crosses zero at the strike")
    out: dict[str, str] = {"heel_strike": guard}
    for key, allowed in (("reset", EVENT_RESETS), ("trailing_foot", TRAILING_FOOT_RULES)):
        if key in tab:
            v = tab[key]
            if v not in allowed:
                raise ModelDescriptionError(
                    f"events.{key}: must be one of {list(allowed)}, got {v!r}")
            out[key] = v
    if desc.root.mirror is None:
        raise ModelDescriptionError(
            f"events.reset: 'swap_legs' relabels the links by their mirrors, and the root "
            f"link {desc.root.name!r} declares no mirror")
    return EventsSpec(**out)


def _parse_swap(
    raw: Any, params: Mapping[str, float], desc: WalkerDescription
) -> tuple[tuple[str, str], ...]:
    """Validate the optional ``[swap]`` table: ``k = "j"`` says that after the leg swap the
    parameter ``k`` takes the value ``j`` had. A pair given one way is completed the other way
    (the swap is an involution); both must be parameters (not coordinates: the leg swap
    relabels those by the links' mirrors), distinct, and mirrors must be declared."""
    tab = _table(raw, "swap")
    coords = desc.coordinate_names
    pairs: dict[str, str] = {}
    for k, v in tab.items():
        p = f"swap.{k}"
        for name in (k, v):
            if isinstance(name, str) and name in coords and name not in params:
                raise ModelDescriptionError(
                    f"{p}: {name!r} is a coordinate, not a parameter: [swap] pairs parameters "
                    "whose values the legs exchange (the leg swap relabels the coordinates "
                    "itself, by the links' mirrors)")
        if k not in params:
            raise ModelDescriptionError(f"{p}: unknown parameter {k!r}")
        if not isinstance(v, str) or v not in params:
            raise ModelDescriptionError(
                f"{p}: must name the parameter whose value {k!r} takes after the leg swap "
                f"(one of {sorted(params)}), got {v!r}")
        if k == v:
            raise ModelDescriptionError(
                f"{p}: pairs {k!r} with itself, which exchanges nothing: name the other leg's "
                f"parameter whose value {k!r} takes after the leg swap (a parameter both legs "
                "share is simply left out of [swap])")
        if k == "g" or v == "g":
            raise ModelDescriptionError(f"{p}: gravity 'g' belongs to no leg")
        for a, b in ((k, v), (v, k)):
            if pairs.get(a, b) != b:
                raise ModelDescriptionError(
                    f"{p}: {a!r} is swapped with both {pairs[a]!r} and {b!r} (the swap "
                    "exchanges parameters in pairs)")
            pairs[a] = b
    if pairs and not any(lk.mirror is not None for lk in desc.links):
        raise ModelDescriptionError(
            "swap: the walker declares no link mirrors, so it has no leg swap to exchange "
            "parameters at")
    return tuple(sorted(pairs.items()))


def _parse_powered(raw: Any) -> PoweredSpec:
    """Validate the optional ``[powered]`` table (the default powered target)."""
    tab = _table(raw, "powered")
    _check_keys(tab, _POWERED_KEYS, _POWERED_REQUIRED, "powered")
    v = tab["speed"]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ModelDescriptionError(
            f"powered.speed: must be a number (m/s), not {type(v).__name__}"
        )
    if not (math.isfinite(v) and v > 0):
        raise ModelDescriptionError(f"powered.speed: must be finite and > 0 (m/s), got {v:g}")
    return PoweredSpec(speed=float(v))


def read_description(path: str | Path) -> WalkerDescription:
    """Read and validate a TOML walker description.

    Raises
    ------
    ModelDescriptionError
        On TOML syntax errors or a malformed description (message names the field).
    """
    p = Path(path)
    # opened non-blocking: a FIFO given as the file is refused below instead of hanging the open
    with os.fdopen(os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)), "rb") as fh:
        if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
            raise ModelDescriptionError(f"{p}: not a regular file")
        raw = fh.read(MAX_DESCRIPTION_BYTES + 1)
    if len(raw) > MAX_DESCRIPTION_BYTES:
        raise ModelDescriptionError(
            f"{p.name}: larger than {MAX_DESCRIPTION_BYTES} bytes: not a walker description"
        )
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ModelDescriptionError(f"{p.name}: not UTF-8 text") from exc
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise ModelDescriptionError(f"{p.name}: invalid TOML: {exc}") from exc
    return parse_description(data, source=str(p))
