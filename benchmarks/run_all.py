"""Run every ``benchmarks/bench_*.py`` and print (optionally: store) their result tables.

Usage::

    python benchmarks/run_all.py                 # run all, print tables
    python benchmarks/run_all.py --update-readme # also rewrite the results in README.md
    python benchmarks/run_all.py --quick -k impact
    python benchmarks/run_all.py -k cli          # run one, save its results/bench_cli.json
    python benchmarks/run_all.py --from-results --update-readme   # tables of the saved results

Each benchmark runs in its own process, one after the other (never concurrently: they would
compete for the cores). A benchmark script must accept ``--json PATH`` (and ``--quick``) and
write a dict with a ``rows`` list; its module must define ``format_table(result) -> str``.
Results are also saved as ``benchmarks/results/<name>.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from types import ModuleType

HERE = Path(__file__).resolve().parent
START = "<!-- results:start -->"
END = "<!-- results:end -->"


def _load(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(path.stem, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="pass --quick to every benchmark")
    parser.add_argument("-k", default="", help="run only benchmarks whose name contains this")
    parser.add_argument("--update-readme", action="store_true",
                        help="replace the results section of benchmarks/README.md")
    parser.add_argument("--from-results", action="store_true",
                        help="run nothing: the tables of the saved benchmarks/results/*.json")
    args = parser.parse_args(argv)
    (HERE / "results").mkdir(exist_ok=True)
    tables = []
    failed = []
    for script in sorted(HERE.glob("bench_*.py")):
        if args.k not in script.stem:
            continue
        if args.from_results:
            saved = HERE / "results" / f"{script.stem}.json"
            if not saved.exists():
                failed.append(f"{script.name} (no saved result)")
                continue
            tables.append(_load(script).format_table(json.loads(saved.read_text())))
            continue
        print(f"== {script.name}", flush=True)
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "result.json"
            cmd = [sys.executable, str(script), "--json", str(out)]
            if args.quick:
                cmd.append("--quick")
            proc = subprocess.run(cmd, check=False)
            if proc.returncode != 0 or not out.exists():
                failed.append(script.name)
                continue
            result = json.loads(out.read_text())
        (HERE / "results" / f"{script.stem}.json").write_text(json.dumps(result, indent=2))
        tables.append(_load(script).format_table(result))
    if args.update_readme and tables and not args.quick:
        readme = HERE / "README.md"
        text = readme.read_text()
        if START not in text or END not in text:
            print(f"README.md has no {START} ... {END} section; not updated", file=sys.stderr)
        else:
            head, rest = text.split(START, 1)
            _, tail = rest.split(END, 1)
            readme.write_text(head + START + "\n" + "\n\n".join(tables) + "\n" + END + tail)
            print(f"updated {readme}")
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
