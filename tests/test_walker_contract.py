"""The walker contract (issue 9, item 1): every walker answers what analyses ask, and nothing
above ``heelstrike.models`` asks a walker what class it is or falls back on a default."""

from __future__ import annotations

import ast
import copy
import dataclasses
import functools
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np
import pytest

from heelstrike.dynamics.actuation import mechanical_energy
from heelstrike.dynamics.compiled import PARAMETER_NAMES, walker_parameters
from heelstrike.dynamics.phased import PhasedWalker
from heelstrike.models import CompassGait, PlanarWalker, load_walker
from heelstrike.models.base import WalkerScale
from heelstrike.models.builder import shipped_walkers
from heelstrike.models.description import WalkerDescription

SRC = Path(__file__).resolve().parents[1] / "src" / "heelstrike"
SHIPPED = ("compass", "kneed", "torso")


def _walkers() -> Iterator[tuple[str, PlanarWalker]]:
    yield "CompassGait", CompassGait(foot_radius=0.2)
    for name in SHIPPED:
        yield name, load_walker(name)
        yield f"{name} (phased)", PhasedWalker.from_built(load_walker(name))


WALKERS = dict(_walkers())


def test_every_shipped_walker_is_checked() -> None:
    assert set(SHIPPED) <= set(shipped_walkers())


@pytest.mark.parametrize("name", WALKERS)
def test_walker_implements_the_contract(name: str) -> None:
    w = WALKERS[name]
    # named parameters: a read-only mapping of floats (one walker)
    params = w.parameters
    assert isinstance(params, Mapping) and params
    assert all(isinstance(k, str) and isinstance(v, float) for k, v in params.items())
    with pytest.raises(TypeError):
        params["x"] = 1.0  # type: ignore[index]
    assert w.parameter_shape == () and w.is_batched is False
    # scale: scalars in SI units, leg length longer than the stance foot radius
    s = w.scale
    assert isinstance(s, WalkerScale)
    m, g, l = (float(np.asarray(v)) for v in s)
    assert np.shape(s.total_mass) == np.shape(s.gravity) == np.shape(s.leg_length) == ()
    assert m > 0 and g == pytest.approx(9.81) and l >= float(np.asarray(w.foot_radii[0])) >= 0
    # description: None for the hand-written compass, the file's description otherwise
    if isinstance(w, CompassGait):
        assert w.description is None
    else:
        assert isinstance(w.description, WalkerDescription)
        assert tuple(w.parameters) == w.description.param_names
    # backends: scipy always; the compass has the hand-written kernel, described walkers the
    # generated one
    assert w.compiled_kernel == ("compass" if isinstance(w, CompassGait) else "generated")
    assert w.backends == ("scipy", "compiled")
    assert w.supports("scipy") and w.supports("compiled") and not w.supports("numba")
    # Poincare section: angles first, then their rates (and more rates)
    assert w.has_poincare_section is (isinstance(w, CompassGait | PhasedWalker))
    if w.has_poincare_section:
        names = w.section_names
        k = w.n_section_angles
        assert 1 <= k < len(names)
        assert all(f"{a}_dot" in names[k:] for a in names[:k])
        assert all(r.endswith("_dot") for r in names[k:])
        q, qd = w.section_to_state(np.linspace(0.1, 0.3, len(names)))
        assert q.shape == qd.shape == (w.n_coordinates,)


@pytest.mark.parametrize("name", WALKERS)
def test_replace_returns_a_new_frozen_walker(name: str) -> None:
    w = WALKERS[name]
    key = "foot_radius" if isinstance(w, CompassGait) else "R"
    w2 = w.replace(**{key: 0.05})
    assert w2 is not w and type(w2) is type(w)
    assert w2.parameters[key] == 0.05 and w.parameters[key] != 0.05
    assert {k: v for k, v in w2.parameters.items() if k != key} == {
        k: v for k, v in w.parameters.items() if k != key
    }
    for obj in (w, w2):
        with pytest.raises(dataclasses.FrozenInstanceError):
            obj.leg_length = 2.0  # type: ignore[attr-defined]
        with pytest.raises(dataclasses.FrozenInstanceError):
            obj.coordinate_names = ("a",)
    # the copy is a walker with the new value: its foot radius (m) changed
    assert float(np.asarray(w2.foot_radii[0])) == pytest.approx(0.05)


def test_a_copied_built_walker_stays_frozen() -> None:
    w = load_walker("kneed", R=0.2)
    w2 = copy.copy(w)
    assert w2 is not w and dict(w2.parameters) == dict(w.parameters)
    with pytest.raises(dataclasses.FrozenInstanceError):
        w2.description = None  # type: ignore[assignment,misc]


def test_batched_walkers_report_their_parameter_shape() -> None:
    radii = np.array([0.0, 0.1, 0.2])
    c = CompassGait(foot_radius=radii)
    b = load_walker("compass", R=radii)
    assert c.parameter_shape == b.parameter_shape == (3,)
    assert c.is_batched and b.is_batched
    assert CompassGait(foot_radius=radii[:, None], leg_mass=radii + 1).parameter_shape == (3, 3)


def test_from_built_keeps_a_phased_walker_and_builds_one_otherwise() -> None:
    built = load_walker("kneed")
    pw = PhasedWalker.from_built(built)
    assert pw is not built and pw.has_poincare_section and not built.has_poincare_section
    assert PhasedWalker.from_built(pw) is pw


def test_walker_parameters_come_from_the_named_parameters() -> None:
    w = CompassGait(foot_radius=np.array([0.1, 0.3]), leg_inertia=0.02, gravity=3.7)
    rows = walker_parameters(w, slope=0.05)
    assert rows.shape == (2, 8)
    for k, name in enumerate(PARAMETER_NAMES[:-1]):
        np.testing.assert_array_equal(rows[:, k], np.broadcast_to(w.parameters[name], (2,)))
    np.testing.assert_array_equal(rows[:, -1], 0.05)
    with pytest.raises(TypeError, match="CompassGait"):
        walker_parameters(load_walker("compass"))


@pytest.mark.parametrize("slope", [0.0, 0.05])
def test_compass_energy_fast_path_equals_the_generic_energy(slope: float) -> None:
    w = CompassGait(foot_radius=0.3, leg_inertia=0.05)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = np.array([0.2, 0.3, *rng.uniform(-0.5, 0.5, 2)])
        qd = rng.normal(size=4)
        generic = 0.5 * qd @ w.mass_matrix(q) @ qd + w.potential_energy(q, slope)
        assert float(mechanical_energy(w, q, qd, slope)) == pytest.approx(generic, rel=1e-13)
        # the same walker in a batch of one takes the generic path
        wb = w.replace(foot_radius=np.array([0.3]))
        assert float(mechanical_energy(wb, q, qd, slope)[0]) == pytest.approx(generic, rel=1e-13)


# -- the layout rule: no class tests and no fallbacks on walkers above models/ ----------------
#: Where the rule holds: everything that uses walkers without being one.
RULE_PATHS = (
    "analysis", "dynamics", "plots", "cli", "cli.py", "cli_robot.py", "outputs.py", "io.py",
)
#: Objects ``getattr``/``hasattr`` may probe: argparse namespaces and modules.
ALLOWED_OBJECTS = frozenset({"args", "namespace", "module", "mod"})


@functools.cache
def _walker_classes() -> frozenset[str]:
    """Names of every class deriving from PlanarWalker anywhere in the package.

    ``PlanarWalker`` itself (the contract) is left out: checking that an argument is a walker
    at all is input validation, not asking which walker it is.
    """
    bases: dict[str, set[str]] = {}
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ClassDef):
                bases.setdefault(node.name, set()).update(
                    b.id if isinstance(b, ast.Name) else b.attr
                    for b in node.bases
                    if isinstance(b, ast.Name | ast.Attribute)
                )
    found = {"PlanarWalker"}
    while True:
        more = {c for c, bs in bases.items() if bs & found} - found
        if not more:
            return frozenset(found - {"PlanarWalker"})
        found |= more


@functools.cache
def _walker_attributes() -> frozenset[str]:
    """Public attribute names of the walkers and of their descriptions (not dunders)."""
    names: set[str] = set()
    for obj in (*WALKERS.values(), WalkerDescription):
        names |= {n for n in dir(obj) if not n.startswith("__")}
        names |= set(getattr(obj, "__dict__", {}))
    return frozenset(n for n in names if not n.startswith("__"))


def _root_name(node: ast.expr) -> str | None:
    """``walker`` for ``walker``, ``pmap.walker`` or ``self.walker``; None for other forms."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def _walkerish(name: str | None) -> bool:
    return name is not None and (
        "walker" in name.lower() or "model" in name.lower() or "desc" in name.lower()
        or name in {"w", "w0", "w2", "pw", "wk"}
    )


def _is_module(node: ast.expr) -> bool:
    return isinstance(node, ast.Call) and _root_name(node.func) == "import_module"


def violations(source: str, filename: str = "<src>") -> list[str]:
    """Class tests of walkers and attribute probes with a fallback on walkers in ``source``.

    Flagged: ``isinstance``/``issubclass`` (and ``type(x) is C``) naming a walker class (a
    subclass of ``PlanarWalker``); and
    ``getattr(obj, name, default)`` or ``hasattr(obj, name)`` unless ``obj`` is an argparse
    namespace or a module (:data:`ALLOWED_OBJECTS`, ``importlib.import_module(...)``), when the
    object is named like a walker/model/description or ``name`` is a walker attribute.
    """
    classes = _walker_classes()
    attributes = _walker_attributes()
    out = []
    for node in ast.walk(ast.parse(source, filename)):
        where = f"{filename}:{getattr(node, 'lineno', 0)}"
        if isinstance(node, ast.Call) and _root_name(node.func) in ("isinstance", "issubclass"):
            if len(node.args) == 2:
                target = node.args[1]
                elts = target.elts if isinstance(target, ast.Tuple) else [target]
                for e in elts:
                    parts = [e.left, e.right] if isinstance(e, ast.BinOp) else [e]
                    if any(_root_name(p) in classes for p in parts):
                        out.append(f"{where}: {ast.unparse(node)}")
        elif isinstance(node, ast.Compare) and any(
            isinstance(op, ast.Is | ast.IsNot | ast.Eq | ast.NotEq) for op in node.ops
        ):
            sides = [node.left, *node.comparators]
            if any(isinstance(s, ast.Call) and _root_name(s.func) == "type" for s in sides) and any(
                _root_name(s) in classes for s in sides
            ):
                out.append(f"{where}: {ast.unparse(node)}")
        elif isinstance(node, ast.Call) and _root_name(node.func) in ("getattr", "hasattr"):
            probe = node.func.id == "hasattr" if isinstance(node.func, ast.Name) else False
            has_default = len(node.args) == 3 or probe
            if not has_default or len(node.args) < 2:
                continue
            obj, attr = node.args[0], node.args[1]
            if _root_name(obj) in ALLOWED_OBJECTS or _is_module(obj):
                continue
            attr_name = attr.value if isinstance(attr, ast.Constant) else None
            if _walkerish(_root_name(obj)) or (
                isinstance(attr_name, str) and attr_name in attributes
            ):
                out.append(f"{where}: {ast.unparse(node)}")
    return out


def _rule_files() -> list[Path]:
    files: list[Path] = []
    for entry in RULE_PATHS:
        p = SRC / entry
        if p.is_dir():
            files += sorted(p.rglob("*.py"))
        elif p.is_file():
            files.append(p)
    return files


def test_the_rule_finds_what_it_forbids() -> None:
    bad = {
        "isinstance(walker, CompassGait)": 1,
        "isinstance(w, (BuiltWalker, float))": 1,
        "isinstance(x, PhasedWalker | None)": 1,
        "type(w) is CompassGait": 1,
        "issubclass(cls, BuiltWalker)": 1,
        "getattr(walker, 'leg_length', 1.0)": 1,
        "getattr(pmap.walker, 'gravity', None)": 1,
        "getattr(thing, 'leg_length', 1.0)": 1,  # a walker attribute on any object
        "getattr(desc, 'structure_key', None)": 1,
        "hasattr(walker, 'leg_length')": 1,
        "hasattr(obj, 'foot_radius')": 1,
    }
    for src, n in bad.items():
        assert len(violations(src)) == n, src
    fine = [
        "isinstance(x, float)",
        "isinstance(result, PhasedWalkResult)",
        "isinstance(walker, PlanarWalker)",  # a walker at all: input validation
        "getattr(walker, 'leg_length')",  # no fallback: an AttributeError if absent
        "getattr(args, 'model', None)",
        "getattr(importlib.import_module('m'), 'x', None)",
        "getattr(module, '__file__', None)",
        "getattr(func, 'py_func', None)",
    ]
    for src in fine:
        assert violations(src) == [], src
    assert {"CompassGait", "BuiltWalker", "PhasedWalker"} <= _walker_classes()


def test_no_walker_class_tests_or_fallbacks_above_models() -> None:
    files = _rule_files()
    assert any(f.parent.name == "analysis" for f in files)
    assert any(f.parent.name == "dynamics" for f in files)
    found = [v for f in files for v in violations(f.read_text(), str(f.relative_to(SRC)))]
    assert found == []


def test_section_point_is_one_layout_for_every_walker() -> None:
    """``section_point``: the compass's ``(q3, q3_dot, q4_dot)`` on any walker's section, with
    further links (the torso) starting upright and not turning (absolute angle and rate 0)."""
    import numpy as np

    from heelstrike.dynamics.phased import load_phased_walker
    from heelstrike.models import CompassGait

    np.testing.assert_array_equal(CompassGait().section_point(-0.2, 1.1, 0.3), [-0.2, 1.1, 0.3])
    torso = load_phased_walker("torso")
    q, qd = torso.section_to_state(torso.section_point(-0.2, 1.1, 0.3))
    j = torso.joint_index("torso")
    assert q[2] == -0.2 and qd[2] == 1.1
    assert abs(q[2] + q[j]) < 1e-15 and abs(qd[2] + qd[j]) < 1e-15
    kneed = load_phased_walker("kneed")
    q, qd = kneed.section_to_state(kneed.section_point(-0.2, 1.1, 0.3))
    assert q[2] == -0.2 and qd[2] == 1.1 and qd[kneed.joint_index("hip")] == 0.3
