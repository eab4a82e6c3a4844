"""First use: the builds a command announces (estimate) against the time they took (measured).

Each command runs once as a new process with empty caches (``HEELSTRIKE_CACHE_DIR`` and
``NUMBA_CACHE_DIR`` set to new empty temporary folders), as on a new machine. Its stderr is read
for the first-use lines of :mod:`heelstrike._firstuse`: every top-level build's announced
estimate and the time its final line reports. The table gives, per command, each build
(estimated s, measured s, ratio measured / estimated), the sum of the estimates and the
command's whole wall time (imports and the computation after the builds included).

Commands: ``heelstrike gait --radius 0.3 --slope 3deg``, ``heelstrike gait --model kneed`` and
``heelstrike gait --model my_walker.toml`` (a copy of ``kneed.toml``: a walker of the user's own,
run through numba's JIT).
Slow (minutes): the builds are what it measures. Run
``python benchmarks/bench_first_use.py`` (``--quick``: the compass command only; ``--json
PATH``).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from _common import machine, run_main

#: ``{own}`` is a copy of the shipped ``kneed.toml`` in a new folder: a walker file of the
#: user's own, whose kernels run through numba's JIT.
COMMANDS: tuple[tuple[str, ...], ...] = (
    ("gait", "--radius", "0.3", "--slope", "3deg"),
    ("gait", "--model", "kneed"),
    ("gait", "--model", "{own}"),
)

_DURATION = r"(\d+(?:\.\d+)?) s|(\d+) min (\d+) s"
_ANNOUNCE = re.compile(rf"^heelstrike: first use: (.*?); estimated (?:{_DURATION}) on this")
_BUILT = re.compile(rf"^heelstrike: built .* in (?:{_DURATION}) \(estimated")


def seconds(groups: tuple[str | None, ...]) -> float:
    """Seconds from the groups of :data:`_DURATION` (``'42 s'`` or ``'3 min 05 s'``)."""
    s, m, r = groups
    return float(s) if s is not None else 60.0 * int(m or 0) + int(r or 0)


def parse_builds(stderr: str) -> list[dict[str, Any]]:
    """The top-level builds in a command's stderr: what, estimated (s) and measured (s)."""
    builds: list[dict[str, Any]] = []
    for line in stderr.splitlines():
        if m := _ANNOUNCE.match(line):
            builds.append({"what": m.group(1), "estimated_s": seconds(m.groups()[1:4]),
                           "measured_s": None})
        elif (m := _BUILT.match(line)) is not None:
            for b in builds:
                if f"({b['what']}) in " in line and b["measured_s"] is None:
                    b["measured_s"] = seconds(m.groups()[:3])
                    break
    return builds


def run_cold(argv: tuple[str, ...]) -> dict[str, Any]:
    """Run ``heelstrike *argv`` once with empty caches; the builds and the wall time."""
    import importlib.resources

    exe = shutil.which("heelstrike", path=str(Path(sys.executable).parent)) or "heelstrike"
    with tempfile.TemporaryDirectory() as hc, tempfile.TemporaryDirectory() as nc, \
            tempfile.TemporaryDirectory() as mine:
        own = Path(mine) / "my_walker.toml"
        shipped = importlib.resources.files("heelstrike") / "walkers" / "kneed.toml"
        own.write_text(shipped.read_text())
        argv = tuple(a.replace("{own}", str(own)) for a in argv)
        env = {**os.environ, "HEELSTRIKE_CACHE_DIR": hc, "NUMBA_CACHE_DIR": nc}
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        t0 = time.perf_counter()
        proc = subprocess.run([exe, *argv], env=env, capture_output=True, text=True,
                              check=False)
        wall = time.perf_counter() - t0
    builds = parse_builds(proc.stderr)
    return {
        "command": "heelstrike " + " ".join(a if not a.endswith("my_walker.toml")
                                            else "my_walker.toml" for a in argv),
        "returncode": proc.returncode,
        "wall_s": wall,
        "estimated_total_s": sum(b["estimated_s"] for b in builds),
        "measured_builds_s": sum(b["measured_s"] or 0.0 for b in builds),
        "builds": builds,
        "load_after": os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan"),
        "stderr": proc.stderr[-4000:],
    }


def run(*, quick: bool = False) -> dict[str, Any]:
    """Every command of :data:`COMMANDS` (the first only with ``quick``), once, cold."""
    rows = [run_cold(c) for c in (COMMANDS[:1] if quick else COMMANDS)]
    return {"machine": machine(("numpy", "numba", "sympy")), "rows": rows}


def format_table(result: dict[str, Any]) -> str:
    """A markdown table: per command, each build's estimate and measured time."""
    lines = [f"machine: {result['machine']}", "",
             "| command | build | estimated (s) | measured (s) | measured / estimated |",
             "|---|---|---:|---:|---:|"]
    for r in result["rows"]:
        for b in r["builds"]:
            got = b["measured_s"]
            ratio = f"{got / b['estimated_s']:.2f}" if got and b["estimated_s"] else "-"
            lines.append(f"| `{r['command']}` | {b['what']} | {b['estimated_s']:.0f} | "
                         f"{'-' if got is None else f'{got:.0f}'} | {ratio} |")
        total = r["estimated_total_s"]
        lines.append(f"| `{r['command']}` | **all builds** (whole command: {r['wall_s']:.0f} s,"
                     f" exit {r['returncode']}, load after {r['load_after']:.1f}) | "
                     f"{total:.0f} | {r['measured_builds_s']:.0f} | "
                     f"{r['measured_builds_s'] / total if total else float('nan'):.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(run_main(__doc__, run, format_table,
                              quick_help="the compass command only"))
