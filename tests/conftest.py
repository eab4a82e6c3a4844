"""Test-suite options: plain ``pytest`` skips the tests marked ``slow``; ``--runslow`` runs them.

``pytest`` (the README's quick command) runs the fast tests; ``pytest --runslow`` (what CI runs,
``.ci/run``) runs everything. Setting ``HEELSTRIKE_RUNSLOW=1`` has the same effect as
``--runslow``, and selecting the marker explicitly (``pytest -m slow``) runs the slow tests too.
Tests marked ``scale`` are skipped when the ``scale`` extra is not installed.
"""

from __future__ import annotations

import importlib.util
import os

import pytest
from hypothesis import settings

# Numerical property tests must not depend on machine speed: no per-example deadline (hypothesis'
# default of 200 ms fails numerical code on a loaded machine). Loaded before any test module is
# imported, so every @settings(...) in the tests inherits it.
settings.register_profile("heelstrike", deadline=None)
settings.load_profile("heelstrike")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--runslow",
        action="store_true",
        default=False,
        help="also run the tests marked slow (everything, as CI does)",
    )


def _run_slow(config: pytest.Config) -> bool:
    if config.getoption("--runslow"):
        return True
    if os.environ.get("HEELSTRIKE_RUNSLOW", "").strip().lower() in ("1", "true", "yes"):
        return True
    return "slow" in (config.getoption("markexpr", "") or "")


def _scale_installed() -> bool:
    """Whether the ``scale`` extra (dask, distributed, zarr, netCDF4, filelock) is importable."""
    return all(importlib.util.find_spec(m) is not None
               for m in ("dask", "distributed", "zarr", "netCDF4", "filelock"))


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    # under CI the extra is installed: a missing one must fail the tests, not skip them
    if not _scale_installed() and not os.environ.get("CI"):
        need = pytest.mark.skip(reason="needs the scale extra: pip install '.[scale]'")
        for item in items:
            if "scale" in item.keywords:
                item.add_marker(need)
    if _run_slow(config):
        return
    skip = pytest.mark.skip(reason="slow: run with pytest --runslow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
