"""Walker files are data: nothing in them, nor in the cache, runs as code (issue 11, items 1-4)."""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from heelstrike.core import impact
from heelstrike.models import builder as builder_mod
from heelstrike.models._generated import (
    CacheWarning,
    UnsafeGeneratedCode,
    load_source,
    verify_source,
)
from heelstrike.models.builder import GENERATED_FUNCTIONS, BuiltWalker, build, load_walker
from heelstrike.models.description import (
    MAX_DESCRIPTION_BYTES,
    MAX_LINKS,
    ModelDescriptionError,
    parse_description,
    read_description,
)

WALKERS = Path(builder_mod.__file__).parent.parent / "walkers"
INJECTED_NAME = 'x""";__import__("os").system("touch PWNED");"""'


@pytest.fixture(autouse=True)
def _private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """Each test gets its own cache folder and an empty in-process cache."""
    d = tmp_path / "cache"
    monkeypatch.setenv("HEELSTRIKE_CACHE_DIR", str(d))
    monkeypatch.setattr(builder_mod, "_MEMORY", {})
    monkeypatch.chdir(tmp_path)
    yield d


def _compass_data() -> dict[str, Any]:
    return tomllib.loads((WALKERS / "compass.toml").read_text(encoding="utf-8"))


def _compass_text() -> str:
    return (WALKERS / "compass.toml").read_text(encoding="utf-8")


def _heel_strike_tc(w: BuiltWalker, q3: float, R: float = 0.0) -> float:
    """T_c of the paper's heel strike (q4 = -2 q3, q3_dot = 1, q4_dot = 0, stance rolling)."""
    q = np.array([0.0, R, q3, -2 * q3])
    qd = np.array([-R, 0.0, 1.0, 0.0])
    A = w.contact_jacobian(q, "left")
    return float(impact(w.mass_matrix(q), A, qd).kinetic_energy_constrained)


# -- 1. a walker file's strings never become code --------------------------------------------


def test_injected_name_is_not_executed_and_not_in_the_code(tmp_path: Path) -> None:
    text = re.sub(r'^name = "compass"', f"name = '{INJECTED_NAME}'", _compass_text(), flags=re.M)
    path = tmp_path / "evil.toml"
    path.write_text(text, encoding="utf-8")
    w = load_walker(path)
    assert w.description.name == INJECTED_NAME
    assert not (tmp_path / "PWNED").exists()
    assert "PWNED" not in w.model.source and "import" not in w.model.source
    # again from the disk cache, in a fresh in-process cache
    builder_mod._MEMORY.clear()
    w2 = load_walker(path)
    assert w2.model.from_cache
    assert not (tmp_path / "PWNED").exists()
    assert _heel_strike_tc(w2, 0.3) == pytest.approx(_heel_strike_tc(load_walker("compass"), 0.3))


def test_no_walker_file_string_enters_generated_code() -> None:
    data = _compass_data()
    data["name"] = "zzname"
    data["link"][0]["name"] = "zzstance"
    data["link"][1]["name"] = "zzswing"
    data["link"][1]["joint"]["name"] = "zzjoint"
    data["link"][0]["mirror"] = "zzswing"
    data["link"][1]["mirror"] = "zzstance"
    data["link"][1]["parent"] = "zzstance"
    for ft in data["foot"]:
        ft["link"] = {"stance_leg": "zzstance", "swing_leg": "zzswing"}[ft["link"]]
    data["point_mass"][0]["name"] = "zzhip"
    data["point_mass"][0]["link"] = "zzstance"
    w = BuiltWalker(parse_description(data))
    assert "zz" not in w.model.source
    # parameters appear only as p_<index>: no identifier of the code is a parameter's name
    identifiers = {n.id for n in ast.walk(ast.parse(w.model.source)) if isinstance(n, ast.Name)}
    assert not identifiers & set(w.description.param_names)
    assert {f"p_{i}" for i in range(len(w.description.param_names))} <= identifiers
    assert "zzhip" in w.positions(np.zeros(4))


def test_cli_does_not_run_an_injected_name(tmp_path: Path) -> None:
    text = re.sub(r'^name = "compass"', f"name = '{INJECTED_NAME}'", _compass_text(), flags=re.M)
    path = tmp_path / "evil.toml"
    path.write_text(text, encoding="utf-8")
    env = {**os.environ, "HEELSTRIKE_CACHE_DIR": str(tmp_path / "clicache")}
    for _ in range(2):  # the second run loads the cached module
        out = subprocess.run(
            [sys.executable, "-m", "heelstrike.cli", "impact", "--model", str(path),
             "--angle", "20deg", "--json"],
            capture_output=True, text=True, cwd=tmp_path, env=env, timeout=300,
        )  # fmt: skip
        assert not (tmp_path / "PWNED").exists(), out.stderr
    assert (tmp_path / "clicache" / "models").is_dir()


# -- 2. the cache is verified, permission-checked and keyed by the generator -----------------


def _cached_file() -> tuple[Path, BuiltWalker]:
    w = load_walker("compass")
    assert w.model.path is not None
    builder_mod._MEMORY.clear()
    return w.model.path, w


TAMPERINGS = [
    '\n__import__("os").system("touch PWNED")\n',
    '\nimport os\nos.system("touch PWNED")\n',
    '\ndef mass_matrix(q, p):\n    return open("PWNED", "w")\n',
    "\ndef mass_matrix(q, p):\n    return ().__class__.__bases__[0].__subclasses__()\n",
    '\ndef mass_matrix(q, p):\n    x = [numpy.load("PWNED") for _ in q]\n    return x\n',
    "\ndef mass_matrix(q, p):\n    return numpy.ctypeslib\n",
    '\ndef mass_matrix(q, p):\n    return zeros((4, 4)) + len("x")\n',
    "\nwhile True:\n    pass\n",
    "\nclass X:\n    pass\n",
    "\nN = 5\n",  # a well-formed module with the wrong size is rebuilt too
]


@pytest.mark.parametrize("tamper", TAMPERINGS)
def test_tampered_cache_entry_is_rebuilt_not_run(tmp_path: Path, tamper: str) -> None:
    path, w = _cached_file()
    q = np.array([0.0, 0.0, 0.2, -0.4])
    M_ref = w.mass_matrix(q)
    with open(path, "a", encoding="utf-8") as fh:
        fh.write(tamper)
    with pytest.warns(CacheWarning, match="failed verification"):
        w2 = load_walker("compass")
    assert not w2.model.from_cache
    assert not (tmp_path / "PWNED").exists()
    np.testing.assert_array_equal(w2.mass_matrix(q), M_ref)
    assert "PWNED" not in path.read_text()  # the entry was rewritten


DYNAMICS_TAMPERINGS = [
    '\ndef dynamics_terms(q, qd, p, slope, lead_m, lead_h):\n    return open("PWNED", "w"), q\n',
    "\ndef dynamics_terms(q, qd, p, slope, lead_m, lead_h):\n    return q.__class__, qd\n",
    # plain arithmetic, but a second definition would silently replace the generated one
    "\ndef dynamics_terms(q, qd, p, slope, lead_m, lead_h):\n"
    "    M = zeros(lead_m + (4, 4))\n    h = zeros(lead_h + (4,))\n    return M, h\n",
]


@pytest.mark.parametrize("tamper", DYNAMICS_TAMPERINGS)
def test_tampered_dynamics_terms_is_rebuilt_not_run(tmp_path: Path, tamper: str) -> None:
    """The combined ``(M, h)`` function (the scipy right-hand side's) is verified like the rest."""
    path, w = _cached_file()
    assert "def dynamics_terms(" in path.read_text()
    rng = np.random.default_rng(5)
    q, qd = rng.normal(size=4), rng.normal(size=4)
    with open(path, "a", encoding="utf-8") as fh:
        fh.write(tamper)
    with pytest.warns(CacheWarning, match="failed verification"):
        w2 = load_walker("compass")
    assert not w2.model.from_cache
    assert not (tmp_path / "PWNED").exists()
    M, h = w2.dynamics_terms(q, qd, 0.1)
    np.testing.assert_allclose(M, w.mass_matrix(q), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(h, w.bias_forces(q, qd, 0.1), rtol=1e-13, atol=1e-13)
    assert np.all(np.linalg.eigvalsh(M) > 0)
    assert path.read_text().count("def dynamics_terms(") == 1  # the entry was rewritten


def test_world_writable_or_foreign_cache_entries_are_not_used(tmp_path: Path) -> None:
    path, _ = _cached_file()
    os.chmod(path, 0o666)
    with pytest.warns(CacheWarning, match="writable by group or others"):
        assert not load_walker("compass").model.from_cache
    builder_mod._MEMORY.clear()
    os.chmod(path.parent, 0o777)
    with pytest.warns(CacheWarning, match="writable by group or others"):
        assert not load_walker("compass").model.from_cache
    os.chmod(path.parent, 0o700)
    os.chmod(path, 0o600)
    builder_mod._MEMORY.clear()
    assert load_walker("compass").model.from_cache
    if hasattr(os, "geteuid") and os.geteuid() == 0:  # root can give the file away
        builder_mod._MEMORY.clear()
        os.chown(path, 65534, 65534)
        with pytest.warns(CacheWarning, match="owned by uid 65534"):
            assert not load_walker("compass").model.from_cache


def test_symlinked_cache_entry_is_not_used(tmp_path: Path) -> None:
    path, _ = _cached_file()
    elsewhere = tmp_path / "elsewhere.py"
    elsewhere.write_text(path.read_text())
    path.unlink()
    path.symlink_to(elsewhere)
    with pytest.warns(CacheWarning, match="symbolic link"):
        assert not load_walker("compass").model.from_cache


def test_cache_key_covers_the_generator(monkeypatch: pytest.MonkeyPatch) -> None:
    desc = read_description(WALKERS / "compass.toml")
    key = builder_mod._compute_key(desc)
    # the key a process uses (computed once per description) is this computation's
    assert builder_mod._key(desc) == key
    monkeypatch.setattr(builder_mod, "generator_fingerprint", lambda *_: "changed-generator")
    assert builder_mod._compute_key(desc) != key
    # a new description object (e.g. the next process's) gets the new generator's key
    assert builder_mod._key(read_description(WALKERS / "compass.toml")) != key


def test_keys_are_computed_once_per_description_and_the_cache_is_bounded() -> None:
    from heelstrike.models._generated import IdentityCache

    calls: list[object] = []

    def compute(obj: object) -> str:
        calls.append(obj)
        return f"key-{len(calls)}"

    cache = IdentityCache(compute, maxsize=3)
    a, b = object(), object()
    assert cache(a) == "key-1" and cache(a) == "key-1" and cache(b) == "key-2"
    assert len(calls) == 2  # a's key was computed once
    others = [object() for _ in range(5)]
    for o in others:
        cache(o)
    assert len(cache) == 3  # bounded: the least recently used entries were dropped
    assert cache(a) == "key-8"  # a was dropped, so its key is computed again
    # load_walker reads a new description every call: the builder's cache stays bounded
    for _ in range(140):
        load_walker("compass")
    assert len(builder_mod._key) <= 128


def test_generated_modules_verify_and_run_without_builtins() -> None:
    for name in ("compass", "kneed", "torso"):
        model = build(read_description(WALKERS / f"{name}.toml"))
        verify_source(
            model.source, helpers={"numpy", "zeros", "_lead"}, functions=GENERATED_FUNCTIONS
        )
        assert model.namespace["__builtins__"] == {}


@pytest.mark.parametrize(
    "body",
    [
        "def f(q):\n    return q.__class__\n",
        "def f(q):\n    return getattr(q, 'x')\n",
        "def f(q):\n    return numpy.load\n",
        "def f(q, k=1):\n    return q\n",
        "@numpy.sin\ndef f(q):\n    return q\n",
        "def f(q):\n    global zeros\n    return q\n",
        "def f(q):\n    zeros = 1\n    return q\n",
        "def f(q):\n    return lambda: q\n",
        "def f(q):\n    return 'text'\n",
        "def f(q):\n    return q if q else q\n",
        "def __init__(q):\n    return q\n",
        "def f(q):\n    import os\n    return q\n",
        "def f(q):\n    return q\n\ndef f(q):\n    return q\n",
    ],
)
def test_verifier_rejects(body: str) -> None:
    with pytest.raises(UnsafeGeneratedCode):
        verify_source(body, helpers={"numpy", "zeros"})


def test_verifier_accepts_generator_shapes_and_sandbox_has_no_builtins() -> None:
    src = (
        '"""doc"""\nN = 2\n\ndef f(q, *p):\n    """d"""\n    q0 = q[..., 0]\n    a, b, = p\n'
        "    x0 = numpy.sin(q0)**2 + -a/b\n    out = zeros(_lead(q, *p) + (2,))\n"
        "    out[..., 0] = x0\n    out[..., 1] = numpy.pi\n    return out\n"
    )
    ns = load_source(
        src, "<t>", helpers={"numpy": np, "zeros": np.zeros, "_lead": builder_mod._lead}
    )
    assert ns["__builtins__"] == {}
    np.testing.assert_allclose(
        ns["f"](np.array([0.5, 0.0]), 1.0, 2.0), [np.sin(0.5) ** 2 - 0.5, np.pi]
    )


# -- 3. bounded expressions and model size, progress while deriving --------------------------


@pytest.mark.parametrize(
    ("expr", "pattern"),
    [
        ("9**9**9", r"exponents must be numbers"),
        ("l**100", r"exponents must be numbers"),
        ("l**l", r"exponents must be numbers"),
        ("-" * 100_000 + "l", r"longer than"),
        ("sin(" * 30 + "l" + ")" * 30, r"nested deeper"),
        ("100000000000000000000 * l", r"integer literal too large"),
        ("__import__('os')", r"unsupported expression syntax|unknown parameter"),
        ("l.real", r"unsupported expression syntax"),
    ],
)
def test_unbounded_expressions_are_refused_quickly(expr: str, pattern: str) -> None:
    data = _compass_data()
    data["link"][0]["com"] = expr
    # refused by the parser's bounds before anything is evaluated (a hang would show as one)
    with pytest.raises(ModelDescriptionError, match=rf"^link\[0\]\.com: .*{pattern}"):
        parse_description(data)


def test_bounded_but_legitimate_expressions_still_work() -> None:
    data = _compass_data()
    data["link"][0]["com"] = "sqrt((l - b)**2)"
    w = BuiltWalker(parse_description(data))
    ref = load_walker("compass")
    q = np.array([0.1, 0.0, 0.3, -0.6])
    np.testing.assert_allclose(w.mass_matrix(q), ref.mass_matrix(q), rtol=1e-13)


def test_too_many_links_is_refused() -> None:
    data = _compass_data()
    extra = [
        {"name": f"l{i}", "parent": "swing_leg", "length": 0.1, "mass": 0.1, "com": 0.05}
        for i in range(MAX_LINKS)
    ]
    data["link"] = data["link"] + extra
    with pytest.raises(ModelDescriptionError, match=rf"^link: at most {MAX_LINKS} links"):
        parse_description(data)


def test_derivation_reports_progress(monkeypatch: pytest.MonkeyPatch) -> None:
    import heelstrike.models._codegen as codegen

    seen: dict[str, int] = {"total": 0, "ticks": 0}

    class FakeBar:
        def __init__(self, *_args: Any, total: int, file: Any, delay: float, **_: Any) -> None:
            assert file is sys.stderr and delay > 0
            seen["total"] = total

        def __enter__(self) -> FakeBar:
            return self

        def __exit__(self, *_: object) -> None:
            return None

        def update(self, n: int) -> None:
            seen["ticks"] += n

    monkeypatch.setattr("tqdm.auto.tqdm", FakeBar)
    desc = read_description(WALKERS / "kneed.toml")
    codegen.generate_source(desc, "ab" * 32)
    assert seen["total"] > 0 and seen["ticks"] == seen["total"]


def test_description_file_size_and_kind_are_checked(tmp_path: Path) -> None:
    if Path("/dev/zero").exists():
        with pytest.raises(ModelDescriptionError, match="not a regular file"):
            read_description("/dev/zero")
    big = tmp_path / "big.toml"
    big.write_text(_compass_text() + "#" * (MAX_DESCRIPTION_BYTES + 10))
    with pytest.raises(ModelDescriptionError, match="larger than"):
        read_description(big)


# -- 4. parameter names that would collide with code or each other ---------------------------


@pytest.mark.parametrize(
    "bad", ["ｌ", "None", "class", "slope", "pi", "sqrt", "_x", "__import__", "use_cache", "a-b"]
)
def test_bad_parameter_names_are_refused(bad: str) -> None:
    data = _compass_data()
    data["params"][bad] = 1.0
    with pytest.raises(ModelDescriptionError, match=r"^params\..*invalid parameter name"):
        parse_description(data)


def _rename_parameters(data: dict[str, Any], renames: dict[str, str]) -> dict[str, Any]:
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, renames)) + r")\b")

    def fix(v: Any) -> Any:
        return pattern.sub(lambda m: renames[m.group(1)], v) if isinstance(v, str) else v

    skip = {"name", "parent", "mirror", "link", "direction"}
    out = dict(data)
    out["params"] = {renames.get(k, k): v for k, v in data["params"].items()}
    out["constraints"] = [fix(c) for c in data.get("constraints", [])]
    for section in ("link", "foot", "point_mass"):
        out[section] = [
            {k: (v if k in skip else fix(v)) for k, v in t.items()} for t in data[section]
        ]
    return out


def test_parameter_names_like_generated_identifiers_keep_the_physics() -> None:
    renames = {"l": "q2", "m": "zeros", "b": "numpy", "R": "x0", "I": "p_0", "mH": "u2"}
    data = _rename_parameters(_compass_data(), renames)
    w = BuiltWalker(parse_description(data), x0=0.25)
    ref = load_walker("compass", R=0.25)
    rng = np.random.default_rng(1)
    q, qd = rng.normal(size=(6, 4)), rng.normal(size=(6, 4))
    np.testing.assert_allclose(w.mass_matrix(q), ref.mass_matrix(q), rtol=1e-13)
    np.testing.assert_allclose(
        w.bias_forces(q, qd, 0.1), ref.bias_forces(q, qd, 0.1), rtol=1e-12, atol=1e-12
    )
    # the paper's value for R = 0.25, q3 = 20 deg: T_c = 2.22 J (README), unchanged by names
    q3 = float(np.deg2rad(20.0))
    tc = _heel_strike_tc(w, q3, R=0.25)
    assert tc == pytest.approx(_heel_strike_tc(ref, q3, R=0.25), rel=1e-12)
    assert tc == pytest.approx(2.22, abs=0.005)


def test_an_unused_parameter_cannot_remove_the_slope() -> None:
    data = _compass_data()
    data["params"]["slope"] = 0.0
    with pytest.raises(ModelDescriptionError, match=r"^params\.slope"):
        parse_description(data)


# -- declared parameter constraints -----------------------------------------------------------


def test_declared_constraints_are_checked_on_every_value() -> None:
    data = _compass_data()
    data["constraints"] = ["0 <= R <= l", "b <= l"]
    desc = parse_description(data)
    w = BuiltWalker(desc, R=0.5)
    with pytest.raises(
        ModelDescriptionError, match=r"^constraints\[0\]: '0 <= R <= l' is violated"
    ):
        BuiltWalker(desc, R=2.0)
    with pytest.raises(
        ModelDescriptionError, match=r"^constraints\[1\]: 'b <= l' is violated \(b=1.5, l=1\)"
    ):
        w.replace(b=1.5)
    with pytest.raises(ModelDescriptionError, match=r"^constraints\[0\]"):
        BuiltWalker(desc, R=np.array([0.1, 1.2]))  # arrays: every entry must satisfy it
    for bad in ("R = l", "R + l", "R <= zz", "R == l", 3):
        data["constraints"] = [bad]
        with pytest.raises(ModelDescriptionError, match=r"^constraints\[0\]"):
            parse_description(data)


def test_a_fifo_is_refused_not_waited_on(tmp_path: Path) -> None:
    # the description reader opened the file before checking its type: a FIFO (no writer)
    # blocked the open for ever, in the API (the CLI refused it by a check of its own)
    fifo = tmp_path / "walker.toml"
    os.mkfifo(fifo)
    code = ("import sys\nfrom heelstrike.models.description import read_description\n"
            "try:\n    read_description(sys.argv[1])\nexcept ValueError as e:\n    print(e)\n")
    res = subprocess.run([sys.executable, "-c", code, str(fifo)], capture_output=True,
                         text=True, timeout=120, check=False)  # a hang is killed, not waited on
    assert res.returncode == 0 and "not a regular file" in res.stdout, res.stderr
