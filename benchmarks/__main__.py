"""One command for every benchmark: prints one table and writes JSON.

    python -m benchmarks [--json benchmarks/results.json] [--only pipeline,decode,envs]

Each module's ``measure()`` returns rows; a row's ratio compares it with a reference row
measured in the same run (> 1: faster than the reference), since these machines are shared
and noisy. Targets are checked and printed at the end.
"""

import argparse
import importlib
import json
import platform
import sys
from pathlib import Path

MODULES = ("pipeline", "decode", "envs", "controllers", "openr", "match")


def machine() -> str:
    cpu = (
        next(
            (
                line.split(":", 1)[1].strip()
                for line in Path("/proc/cpuinfo").read_text().splitlines()
                if line.startswith("model name")
            ),
            platform.processor(),
        )
        if Path("/proc/cpuinfo").exists()
        else ""
    )
    import os

    return (
        f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}, Python {platform.python_version()}"
    )


def table(rows: list[dict]) -> str:
    lines = ["| measurement | value | ratio to reference |", "|---|---|---|"]
    for r in rows:
        ratio = f"{r['ratio']:.2f}x {r['reference']}" if r["ratio"] is not None else ""
        lines.append(f"| {r['name']} | {r['value']:.4g} {r['unit']} | {ratio} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    parser.add_argument("--json", default="benchmarks/results.json", help="where to write the rows as JSON")
    parser.add_argument("--only", default=",".join(MODULES), help="comma-separated modules to run")
    args = parser.parse_args(argv)
    names = [n for n in args.only.split(",") if n]
    unknown = sorted(set(names) - set(MODULES))
    if unknown or not names:
        parser.error(
            f"unknown benchmark module(s): {', '.join(unknown) or '(none given)'}; choose from {', '.join(MODULES)}"
        )
    rows, failed = [], []
    for name in names:
        print(f"running benchmarks.{name} ...", file=sys.stderr, flush=True)
        try:
            rows += importlib.import_module(f"benchmarks.{name}").measure()
        except Exception as error:  # a missing tool or package: the other modules' rows still count
            message = str(error).strip().splitlines()
            failed.append(f"benchmarks.{name}: {type(error).__name__}: {message[-1] if message else ''}")
            print(f"  failed: benchmarks.{name}: {type(error).__name__}: {error}", file=sys.stderr, flush=True)
    print(f"Machine: {machine()}\n")
    print(table(rows))
    print("\nTargets (issue 7):")
    for r in rows:
        if "target" in r:
            measured = r["ratio"] if r["target"].startswith("ratio") else r["value"]
            print(f"  {'met   ' if r['met'] else 'MISSED'} {r['name']}: {measured:.4g}, target {r['target']}")
    for line in failed:
        print(f"  NOT MEASURED {line}")
    Path(args.json).write_text(json.dumps({"machine": machine(), "rows": rows, "failed": failed}, indent=2) + "\n")
    print(f"\nwrote {args.json}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
