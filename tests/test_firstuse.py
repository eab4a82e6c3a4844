"""The first-use estimate model and its messages (no timing: the probe and clock are given)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

import heelstrike._firstuse as fu


def test_estimate_is_size_times_rate_times_probe_reference_first() -> None:
    est = fu.estimate("aot-walker", 2000.0, 0.25, {})
    assert est.seconds == pytest.approx(2000.0 * fu.KINDS["aot-walker"].k * 0.25)
    assert "reference rate" in est.basis and "2000 lines" in est.basis and "250 ms" in est.basis
    # a loaded machine: the load factor multiplies the time
    loaded = fu.estimate("aot-walker", 2000.0, 0.25, {}, load=3.0)
    assert loaded.seconds == pytest.approx(3**fu.LOAD_PERSISTENCE * est.seconds)
    assert "load factor 3.0" in loaded.basis
    # twice the size, or a machine twice as slow: twice the time
    assert fu.estimate("aot-walker", 4000.0, 0.25, {}).seconds == pytest.approx(2 * est.seconds)
    assert fu.estimate("aot-walker", 2000.0, 0.5, {}).seconds == pytest.approx(2 * est.seconds)


def test_load_factor_is_the_inverse_share_of_a_core_at_least_one() -> None:
    assert fu.load_factor(0.25) == 4.0  # a quarter of a core: 4 times slower
    assert fu.load_factor(1.0) == 1.0
    assert fu.load_factor(1.7) == 1.0  # never faster than alone
    assert fu.load_factor(window=0.05) >= 1.0  # measured
    first = fu.current_load()
    assert first >= 1.0 and fu.current_load() == first  # reused, not measured again


def test_recorded_builds_replace_the_reference_by_their_median() -> None:
    records = {"jit": [0.5, 0.1, 0.3], "aot-compass": [9.0]}
    est = fu.estimate("jit", 100.0, 0.2, records)
    assert est.seconds == pytest.approx(100.0 * 0.3 * 0.2)
    assert "3 earlier builds here" in est.basis
    assert "1 earlier build here" in fu.estimate("aot-compass", 1.0, 1.0, records).basis
    with pytest.raises(KeyError):
        fu.estimate("no such kind", 1.0, 1.0, {})


def test_record_writes_the_normalised_rate_and_keeps_the_last_ones(tmp_path: Path) -> None:
    path = tmp_path / "c" / fu.RATES_FILE
    fu.record(path, "jit", 200.0, 10.0, 0.25, load=4.0)
    damped = 4.0**fu.LOAD_PERSISTENCE
    assert fu.read_records(path) == {"jit": [pytest.approx(10.0 / (200.0 * 0.25 * damped))]}
    # the next estimate of the same build on the same machine under the same load is the time
    # it took; on an idle machine less
    rec = fu.read_records(path)
    assert fu.estimate("jit", 200.0, 0.25, rec, load=4.0).seconds == pytest.approx(10.0)
    assert fu.estimate("jit", 200.0, 0.25, rec).seconds == pytest.approx(10.0 / damped)
    for s in range(1, 20):
        fu.record(path, "jit", 1.0, float(s), 1.0)
    kept = fu.read_records(path)["jit"]
    assert kept == [float(s) for s in range(20 - fu.KEEP, 20)]
    fu.record(path, "jit", 0.0, 1.0, 1.0)  # nothing to learn from a zero size
    assert len(fu.read_records(path)["jit"]) == fu.KEEP
    assert json.loads(path.read_text())["format"] == "heelstrike-build-rates-1"
    path.write_text("{not json")
    assert fu.read_records(path) == {}


def test_messages_name_the_estimate_the_time_and_the_cache() -> None:
    est = fu.Estimate(seconds=125.0, basis="1900 lines at the reference rate")
    before = fu.announce_text("walker 'kneed''s kernels", est, "/c/aot")
    assert before.startswith("heelstrike: first use: walker 'kneed''s kernels")
    assert "estimated 2 min 05 s" in before and "/c/aot" in before and "reference" in before
    after = fu.finish_text("walker 'kneed''s kernels", "mod.so", 81.3, est, "/c/aot")
    assert "built mod.so" in after and "in 81 s" in after and "estimated 2 min 05 s" in after
    assert after.endswith("cache: /c/aot")
    assert fu.stage_text(2, 4, "compiling kernel 1 of 2", 3.04) == \
        "heelstrike:   [3.0 s] stage 2 of 4: compiling kernel 1 of 2"
    assert "still compiling" in fu.heartbeat_text("compiling", 30.0, est)


@pytest.fixture
def idle_machine(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Callable[[float], None]:
    """``idle_machine(probe)``: the cache in ``tmp_path``, the probe ``probe`` s, no load."""

    def setup(probe: float) -> None:
        monkeypatch.setenv("HEELSTRIKE_CACHE_DIR", str(tmp_path))
        monkeypatch.setattr(fu._PROBE, "seconds", probe)
        monkeypatch.setattr(fu, "current_load", lambda: 1.0)

    return setup


def test_a_build_announces_stages_and_reports_then_records(
        tmp_path: Path, idle_machine: Callable[[float], None],
        capsys: pytest.CaptureFixture[str],
) -> None:
    idle_machine(0.5)
    rates = tmp_path / fu.RATES_FILE
    fu.record(rates, "aot-compass", 10.0, 20.0, 0.5)  # k = 4: 10 units, 20 s estimated
    with fu.first_use("the test kernels", kind="aot-compass", size=10.0, cache=tmp_path / "aot",
                      stages=2, built="mod.so", heartbeat=None) as b:
        b.stage("one")
        with fu.first_use("an inner derivation", kind="jit", size=1.0, cache="elsewhere",
                          heartbeat=None):
            pass
        b.stage("two")
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("heelstrike: first use: the test kernels; estimated 20 s")
    assert str(tmp_path / "aot") in lines[0]
    assert "stage 1 of 2: one" in lines[1]
    assert "stage 2 of 2: an inner derivation" in lines[2]  # a nested build is a stage
    assert "stage 3 of 2: two" in lines[3]
    assert lines[4].startswith("heelstrike: built mod.so (the test kernels) in ")
    assert lines[4].endswith(f"cache: {tmp_path / 'aot'}") and len(lines) == 5
    assert fu.active() is None


def test_a_failed_build_says_so_and_is_not_recorded(
        tmp_path: Path, idle_machine: Callable[[float], None],
        capsys: pytest.CaptureFixture[str],
) -> None:
    idle_machine(1.0)
    with pytest.raises(RuntimeError, match="no compiler"), \
            fu.first_use("k", kind="aot-walker", size=100.0, cache="c", heartbeat=None):
        raise RuntimeError("no compiler")
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("heelstrike: first use: k;") and "k: failed after" in err[-1]
    assert fu.read_records(tmp_path / fu.RATES_FILE) == {}


def test_small_builds_are_quiet_and_heartbeat_names_what_is_compiled(
        tmp_path: Path, idle_machine: Callable[[float], None],
        capsys: pytest.CaptureFixture[str],
) -> None:
    idle_machine(1e-3)  # estimate far under QUIET_BELOW
    with fu.first_use("tiny", kind="jit", size=1.0, cache="c", heartbeat=None) as b:
        assert b.quiet
        b.quiet = False  # heartbeat text on demand, no thread, no clock in the assertion
        b.stage("compiling")
        b.compiling("_walk_py")
        b.compiling("_integrate")
        b.beat()
    err = capsys.readouterr().err.splitlines()
    assert "still compiling (now: _integrate, function 2 compiled)" in err[-2]


def test_numba_compiles_are_announced_or_named_in_the_build_around_them(
        tmp_path: Path, idle_machine: Callable[[float], None],
        capsys: pytest.CaptureFixture[str],
) -> None:
    idle_machine(1.0)

    def kernel(x: float) -> float:  # 3 lines of source
        y = x + 1.0
        return y

    class Cache:
        _cache_path = "/numba/cache"

    class Dispatcher:  # what numba's event carries
        py_func = kernel
        _cache = Cache()

    # alone: announced as a build of its own (3 lines x k[jit] x 1 s probe), cache named
    fu.numba_compile_started({"dispatcher": Dispatcher()})
    fu.numba_compile_ended(None)
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("heelstrike: first use: numba JIT compile of ")
    assert "kernel" in err[0] and "/numba/cache" in err[0]
    assert f"estimated {3 * fu.KINDS['jit'].k:.1f} s" in err[0]
    assert err[-1].startswith("heelstrike: built ") and err[-1].endswith("cache: /numba/cache")
    # inside an announced build: named in its heartbeat, nothing announced
    with fu.first_use("outer", kind="aot-walker", size=10.0, cache="c", heartbeat=None) as b:
        fu.numba_compile_started({"dispatcher": Dispatcher()})
        fu.numba_compile_ended(None)
        assert b.compiled and "kernel" in b.compiled[0]
    err = capsys.readouterr().err
    assert "numba JIT compile" not in err and fu.active() is None
