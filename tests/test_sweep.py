"""The sweep API: equals direct computation, resumes without recomputing, runs on clusters."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr

from heelstrike.analysis.heel_strike import trailing_foot_lifts
from heelstrike.analysis.sweep import (
    SweepError,
    SweepStoreMismatchError,
    sweep,
    sweep_progress,
)
from heelstrike.core.impact import impact
from heelstrike.models.compass import CompassGait, heel_strike_state
from heelstrike.models.compass_fast import heel_strike_impact

ANGLES = np.linspace(0.02, np.pi / 4, 11)
RADII = np.linspace(0.0, 1.0, 7)
GRID = {"impact_angle": ANGLES, "foot_radius": RADII}
CHUNKS = {"impact_angle": 3, "foot_radius": 2}  # 4 x 4 = 16 chunks, ragged edges
N_CHUNKS = 16


def heel_strike_energies(impact_angle: np.ndarray, foot_radius: np.ndarray) -> dict[str, Any]:
    """Paper heel strike through the reference impact algebra (a sweep function)."""
    walker = CompassGait(foot_radius=foot_radius)
    q, qd = heel_strike_state(walker, impact_angle)
    res = impact(walker.mass_matrix(q), walker.contact_jacobian(q, "left"), qd)
    return {
        "T_c": res.kinetic_energy_constrained,
        "T_a": res.kinetic_energy_admissible,
        "constraint_impulse": res.constraint_impulse,
        # the package's one lift rule (q2_dot+ against l (|q3_dot-| + |q4_dot-|) = 1 m/s here):
        # at R = l, q2_dot+ is round-off whose sign differs between algebras
        "lifts": trailing_foot_lifts(res.velocity_post[..., 1], 1.0),
    }


# A module-level function whose behaviour a test can steer (same code, so same identity).
CONTROL: dict[str, Any] = {"calls": [], "fail_after": None, "lock": threading.Lock()}


class Interrupted(RuntimeError):
    pass


def steered(impact_angle: np.ndarray, foot_radius: np.ndarray) -> dict[str, Any]:
    with CONTROL["lock"]:
        if CONTROL["fail_after"] is not None and len(CONTROL["calls"]) >= CONTROL["fail_after"]:
            raise Interrupted("simulated interruption")
        CONTROL["calls"].append((float(impact_angle.flat[0]), float(foot_radius.flat[0])))
    return heel_strike_energies(impact_angle, foot_radius)


def _direct() -> dict[str, np.ndarray]:
    return heel_strike_energies(ANGLES[:, None], RADII[None, :])


def test_sweep_equals_direct_computation() -> None:
    ds = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False)
    direct = _direct()
    assert ds["T_c"].dims == ("impact_angle", "foot_radius")
    assert ds["constraint_impulse"].dims == ("impact_angle", "foot_radius",
                                             "constraint_impulse_dim0")
    assert ds["lifts"].dtype == bool
    for name in ("T_c", "T_a", "constraint_impulse"):
        np.testing.assert_allclose(ds[name].values, direct[name], rtol=1e-13, atol=1e-15)
    np.testing.assert_array_equal(ds["lifts"].values, direct["lifts"])
    np.testing.assert_array_equal(ds["impact_angle"].values, ANGLES)
    assert ds["impact_angle"].attrs["units"] == "rad"
    assert ds["foot_radius"].attrs["units"] == "m"
    assert ds["T_c"].attrs["units"] == "J"
    assert ds.attrs["sweep_function"].endswith("test_sweep.heel_strike_energies")
    assert "heelstrike_version" in ds.attrs
    # Paper: R = l (McGeer's wheel) loses nothing; T_c falls with R.
    np.testing.assert_allclose(ds["T_c"].sel(foot_radius=1.0).values, 0.0, atol=1e-15)
    assert bool((ds["T_c"].diff("foot_radius") < 0).all())


@pytest.mark.scale
def test_sweep_is_reproducible_and_chunking_independent(tmp_path: Path) -> None:
    a = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False)
    b = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False, scheduler="sync")
    xr.testing.assert_identical(a, b)
    c = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False,
              store=tmp_path / "s.zarr")
    xr.testing.assert_identical(a, c.load())
    d = sweep(heel_strike_energies, GRID, chunks=5, progress=False)
    for name in a.data_vars:
        np.testing.assert_allclose(d[name].values, a[name].values, rtol=1e-13, atol=1e-15)


@pytest.mark.slow
@pytest.mark.scale
def test_sweep_processes_scheduler_equals_threads() -> None:
    a = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False)
    b = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False, scheduler="processes",
              num_workers=2)
    xr.testing.assert_identical(a, b)


@pytest.fixture
def control() -> Any:
    CONTROL["calls"] = []
    CONTROL["fail_after"] = None
    yield CONTROL
    CONTROL["calls"] = []
    CONTROL["fail_after"] = None


@pytest.mark.scale
def test_interrupted_sweep_resumes_without_recomputing(tmp_path: Path, control: Any) -> None:
    store = tmp_path / "sweep.zarr"
    control["fail_after"] = 5
    with pytest.raises(Interrupted):
        sweep(steered, GRID, chunks=CHUNKS, store=store, scheduler="sync", progress=False)
    first = set(control["calls"])
    assert len(first) == 5
    assert sweep_progress(store) == (5, N_CHUNKS)

    control["calls"] = []
    control["fail_after"] = None
    resumed = sweep(steered, GRID, chunks=CHUNKS, store=store, scheduler="sync", progress=False)
    second = control["calls"]
    assert len(second) == N_CHUNKS - 5  # only the missing chunks ran ...
    assert first.isdisjoint(second)  # ... and no finished chunk ran again
    assert sweep_progress(store) == (N_CHUNKS, N_CHUNKS)

    at_once = sweep(steered, GRID, chunks=CHUNKS, progress=False)
    xr.testing.assert_identical(resumed.load(), at_once)

    control["calls"] = []
    again = sweep(steered, GRID, chunks=CHUNKS, store=store, progress=False)
    assert control["calls"] == []  # a finished sweep is just reopened
    xr.testing.assert_identical(again.load(), at_once)


@pytest.mark.scale
def test_interrupted_threaded_sweep_resumes(tmp_path: Path, control: Any) -> None:
    store = tmp_path / "sweep.zarr"
    control["fail_after"] = 7
    with pytest.raises(Interrupted):
        sweep(steered, GRID, chunks=CHUNKS, store=store, scheduler="threads", num_workers=2,
              progress=False)
    finished, total = sweep_progress(store)
    assert 0 < finished <= 7 and total == N_CHUNKS
    control["fail_after"] = None
    resumed = sweep(steered, GRID, chunks=CHUNKS, store=store, num_workers=2, progress=False)
    at_once = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False)
    for name in at_once.data_vars:
        np.testing.assert_array_equal(resumed[name].values, at_once[name].values)


@pytest.mark.scale
def test_store_of_another_sweep_is_refused(tmp_path: Path) -> None:
    store = tmp_path / "s.zarr"
    sweep(heel_strike_energies, GRID, chunks=CHUNKS, store=store, progress=False)
    other_grid = {"impact_angle": ANGLES[:-1], "foot_radius": RADII}
    with pytest.raises(SweepStoreMismatchError, match="grid"):
        sweep(heel_strike_energies, other_grid, chunks=CHUNKS, store=store, progress=False)
    with pytest.raises(SweepStoreMismatchError, match="chunks"):
        sweep(heel_strike_energies, GRID, chunks=4, store=store, progress=False)
    with pytest.raises(SweepStoreMismatchError, match="function"):
        sweep(steered, GRID, chunks=CHUNKS, store=store, progress=False)
    ds = sweep(heel_strike_energies, other_grid, chunks=CHUNKS, store=store, progress=False,
               overwrite=True)
    assert ds.sizes["impact_angle"] == ANGLES.size - 1


@pytest.mark.scale
def test_non_sweep_directory_is_refused(tmp_path: Path) -> None:
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "data.txt").write_text("precious")
    with pytest.raises(SweepError, match="not a heelstrike sweep store"):
        sweep(heel_strike_energies, GRID, store=tmp_path / "x", progress=False)
    assert (tmp_path / "x" / "data.txt").read_text() == "precious"


def _bad_shape(impact_angle: np.ndarray, foot_radius: np.ndarray) -> dict[str, Any]:
    return {"y": np.zeros((4, 4))}


def _too_few_dims(impact_angle: np.ndarray, foot_radius: np.ndarray) -> dict[str, Any]:
    return {"y": np.zeros(3)}


def test_bad_inputs_raise_clear_errors() -> None:
    with pytest.raises(SweepError, match="units"):
        sweep(heel_strike_energies, {"impact_angle": ANGLES, "mystery": RADII}, progress=False)
    with pytest.raises(SweepError, match="1-D"):
        sweep(heel_strike_energies, {"impact_angle": np.ones((2, 2))}, progress=False)
    with pytest.raises(SweepError, match="broadcast"):
        sweep(_bad_shape, GRID, chunks=CHUNKS, progress=False)
    with pytest.raises(SweepError, match="needs >= 2"):
        sweep(_too_few_dims, GRID, chunks=CHUNKS, progress=False)
    with pytest.raises(SweepError, match="not in the grid"):
        sweep(heel_strike_energies, GRID, chunks={"slope": 2}, progress=False)


def test_grid_values_must_be_finite_and_distinct() -> None:
    """QA sweep 5: a NaN grid value was swept (an all-NaN slice no ``sel`` can reach) and a
    repeated one computed twice (``ds.sel`` then returns two rows for one value)."""
    calls = []

    def counted(impact_angle: np.ndarray, foot_radius: np.ndarray) -> dict[str, Any]:
        calls.append(1)
        return heel_strike_energies(impact_angle=impact_angle, foot_radius=foot_radius)

    with pytest.raises(SweepError, match=r"grid\['foot_radius'\] must be finite, got nan at "
                       r"index 1 \(and 1 more\)"):
        sweep(counted, {"impact_angle": ANGLES, "foot_radius": [0.1, np.nan, 0.3, np.inf]},
              progress=False)
    with pytest.raises(SweepError, match=r"grid\['impact_angle'\] repeats 0\.2: every value "
                       "must be distinct"):
        sweep(counted, {"impact_angle": [0.1, 0.2, 0.2], "foot_radius": RADII}, progress=False)
    assert not calls  # refused before anything is computed
    # the same grids without the bad values sweep
    ds = sweep(counted, {"impact_angle": [0.1, 0.2], "foot_radius": [0.1, 0.3]}, progress=False)
    assert ds["T_c"].shape == (2, 2) and calls


def test_units_and_attrs_from_dataarray_grid() -> None:
    grid: dict[str, Any] = {
        "impact_angle": xr.DataArray(ANGLES[:3], dims="impact_angle",
                                     attrs={"units": "rad", "long_name": "impact angle q3"}),
        "foot_radius": RADII[:2],
    }
    ds = sweep(heel_strike_energies, grid, progress=False, units={"T_a": "joule"},
               output_dims={"constraint_impulse": ["row"]})
    assert ds["impact_angle"].attrs == {"units": "rad", "long_name": "impact angle q3"}
    assert ds["T_a"].attrs["units"] == "joule"
    assert ds["constraint_impulse"].dims[-1] == "row"


@pytest.mark.scale
def test_distributed_cluster_equals_local(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    local = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, protocol="tcp://",
        dashboard_address=None,
    ) as cluster:
        # By address first, as a user on another machine would: the sweep's own client is the
        # only one connected (this process's event loop is shared with the in-process cluster).
        by_address = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False,
                           scheduler=cluster.scheduler_address, store=tmp_path / "d.zarr")
        with distributed.Client(cluster) as client:
            by_client = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False,
                              scheduler=client)
            workers = client.run(lambda: threading.get_ident())
    assert len(workers) == 2
    xr.testing.assert_identical(local, by_client)
    xr.testing.assert_identical(local, by_address.load())


def fast_energies(impact_angle: np.ndarray, foot_radius: np.ndarray) -> dict[str, Any]:
    """The same outputs through the compiled heel strike (serial kernel in worker threads)."""
    res = heel_strike_impact(impact_angle, foot_radius=foot_radius)
    return {
        "T_c": res.kinetic_energy_constrained,
        "T_a": res.kinetic_energy_admissible,
        "constraint_impulse": res.constraint_impulse,
        "lifts": trailing_foot_lifts(res.q2_dot_post, 1.0),
    }


def test_sweep_of_fast_path_matches_reference_sweep() -> None:
    ref = sweep(heel_strike_energies, GRID, chunks=CHUNKS, progress=False)
    fast = sweep(fast_energies, GRID, chunks=CHUNKS, progress=False, num_workers=2)
    for name in ("T_c", "T_a", "constraint_impulse"):
        np.testing.assert_allclose(fast[name].values, ref[name].values, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(fast["lifts"].values, ref["lifts"].values)


def test_sweep_identity_is_the_same_in_another_process() -> None:
    """A store written by one process is resumed by another: the identity must not depend on
    the interpreter (hash seed, object addresses, import order)."""
    import json
    import os
    import subprocess
    import sys

    from heelstrike.analysis.gait_map import _map_chunk
    from heelstrike.analysis.sweep import _func_identity

    code = (
        "import functools, json, sys\n"
        "from heelstrike.analysis.sweep import _func_identity\n"
        "from heelstrike.analysis.gait_map import _map_chunk\n"
        "from heelstrike.models.compass import CompassGait\n"
        "f = functools.partial(_map_chunk, walker=(('hip_mass', 10.0),), anchors=((0.0, 1.0),),"
        " anchor_index=0, rtol=1e-9, atol=1e-9)\n"
        "print(json.dumps(_func_identity(f)))\n"
    )
    env = {**os.environ, "PYTHONHASHSEED": "12345"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=120, check=True).stdout
    import functools

    here = _func_identity(functools.partial(
        _map_chunk, walker=(("hip_mass", 10.0),), anchors=((0.0, 1.0),), anchor_index=0,
        rtol=1e-9, atol=1e-9))
    assert json.loads(out) == here
    assert set(here) >= {"name", "code", "closure", "defaults", "globals", "bound", "modules"}
