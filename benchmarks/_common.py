"""What every benchmark script shares: the machine line and the command-line entry point.

Scripts run as ``python benchmarks/bench_x.py`` (the folder is then on ``sys.path``) or through
``run_all.py``, which runs each in a subprocess the same way.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
from collections.abc import Callable, Iterable
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

__all__ = ["machine", "run_main"]


def machine(packages: Iterable[str] = ("numpy", "numba")) -> str:
    """CPU, core count, load average at start and the versions of ``packages``."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    versions = []
    for name in packages:
        try:
            versions.append(f"{name} {version(name)}")
        except PackageNotFoundError:
            versions.append(f"{name} not installed")
    return (
        f"{cpu}, {os.cpu_count()} logical cores, 1-min load average at start {load:.1f}; "
        f"Python {platform.python_version()}, " + ", ".join(versions)
    )


def run_main(
    doc: str | None,
    run: Callable[..., dict[str, Any]],
    format_table: Callable[[dict[str, Any]], str],
    argv: list[str] | None = None,
    *,
    quick_help: str = "small sizes (smoke test)",
) -> int:
    """``--quick`` and ``--json PATH``: run, print the table, optionally save the result."""
    parser = argparse.ArgumentParser(description=(doc or "").splitlines()[0] if doc else None)
    parser.add_argument("--quick", action="store_true", help=quick_help)
    parser.add_argument("--json", type=Path, help="write the result rows to this file")
    args = parser.parse_args(argv)
    result = run(quick=args.quick)
    print(format_table(result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    return 0
