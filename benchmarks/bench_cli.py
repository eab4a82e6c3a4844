"""Commands as users run them: wall time of whole ``heelstrike`` processes (issue 9's targets).

Each command runs as a new process (interpreter start, imports, disk caches warm: one untimed
run first), ``repeats`` times, interleaved round by round so that load changes hit every
command alike; the table gives the median wall time and the ratio to the median of
``heelstrike impact --json`` measured in the same rounds. Targets (issue 9):

- ``gait --radius 0.3 --slope 3deg`` within 3x of ``impact --json``;
- ``gait --model kneed``: compiled backend >= 10x faster than ``--backend scipy``, same answer
  to 1e-8 (checked here on the JSON fixed points);
- ``powered`` for each actuation at R = 0 and 0.3, 0.5 m/s: under 10 s each.

Run ``python benchmarks/bench_cli.py`` (``--quick``: 1 timed round, ``--json PATH``).
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from typing import Any

from _common import machine, run_main

IMPACT = ["impact", "--radius", "0.25", "--angle", "20deg", "--json"]
COMMANDS: dict[str, list[str]] = {
    "impact --json": IMPACT,
    "gait --radius 0.3 --slope 3deg": ["gait", "--radius", "0.3", "--slope", "3deg", "--json"],
    "gait --model kneed (compiled)": ["gait", "--model", "kneed", "--slope", "0.0504rad", "--json"],
    "gait --model kneed --backend scipy": [
        "gait", "--model", "kneed", "--slope", "0.0504rad", "--backend", "scipy", "--json",
    ],
    **{
        f"powered --radius {R} --speed 0.5 --actuation {act}": [
            "powered", "--radius", R, "--speed", "0.5", "--actuation", act, "--json",
        ]
        for act in ("pushoff", "hip-energy", "hip-pd")
        for R in ("0", "0.3")
    },
}  # fmt: skip


def _heelstrike() -> list[str]:
    exe = shutil.which("heelstrike")
    return [exe] if exe else [sys.executable, "-m", "heelstrike"]


def _run(argv: list[str]) -> tuple[float, dict[str, Any] | None, int]:
    t0 = time.perf_counter()
    proc = subprocess.run([*_heelstrike(), *argv], capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    try:
        out = json.loads(proc.stdout) if proc.returncode == 0 else None
    except json.JSONDecodeError:
        out = None
    return wall, out, proc.returncode


def run(quick: bool = False) -> dict[str, Any]:
    repeats = 1 if quick else 5
    for argv in COMMANDS.values():  # warm the disk caches (generated code, numba)
        _run(argv)
    times: dict[str, list[float]] = {k: [] for k in COMMANDS}
    outputs: dict[str, dict[str, Any] | None] = {}
    codes: dict[str, int] = {}
    for _ in range(repeats):
        for name, argv in COMMANDS.items():
            wall, out, code = _run(argv)
            times[name].append(wall)
            outputs[name], codes[name] = out, code
    base = statistics.median(times["impact --json"])
    rows = [
        {
            "command": name,
            "median_s": statistics.median(t),
            "ratio_to_impact": statistics.median(t) / base,
            "exit": codes[name],
            "stable": (outputs[name] or {}).get("stable"),
        }
        for name, t in times.items()
    ]
    notes = [f"{repeats} interleaved rounds after one warm-up run of each command"]
    a = outputs.get("gait --model kneed (compiled)")
    b = outputs.get("gait --model kneed --backend scipy")
    if a and b:
        fa, fb = a["fixed_point"], b["fixed_point"]
        diff = max(abs(float(fa[k]) - float(fb[k])) for k in fa)
        notes.append(f"kneed fixed point, compiled vs scipy: max difference {diff:.2g}")
        t_c = statistics.median(times["gait --model kneed (compiled)"])
        t_s = statistics.median(times["gait --model kneed --backend scipy"])
        notes.append(f"kneed gait process, scipy / compiled: {t_s / t_c:.1f}x")
    return {
        "benchmark": "commands as processes",
        "machine": machine(("numpy", "scipy", "numba")),
        "cpu_count": os.cpu_count(),
        "rows": rows,
        "notes": notes,
    }


def format_table(result: dict[str, Any]) -> str:
    lines = [
        f"**{result['benchmark']}** ({result['machine']})",
        "",
        "| command | median wall (s) | ratio to `impact --json` | exit | stable |",
        "| --- | ---: | ---: | ---: | --- |",
    ]
    for r in result["rows"]:
        stable = "" if r["stable"] is None else str(r["stable"]).lower()
        lines.append(
            f"| `{r['command']}` | {r['median_s']:.3g} | {r['ratio_to_impact']:.2g} | "
            f"{r['exit']} | {stable} |"
        )
    lines += [""] + [f"- {n}" for n in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv, quick_help="one timed round")


if __name__ == "__main__":
    sys.exit(main())
