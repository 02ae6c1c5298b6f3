"""``make bench``: every benchmark section of this folder, one after the other, on this machine.

Usage (in the workspace environment)::

    scripts/env.sh python benchmarks/run.py [--quick | --full] [--only WORD] [--json FILE]

Sections register themselves with ``common.section`` (see common.py: adding one is one
function in a module of this folder). Each prints its own tables; a failing section is
reported and the others still run (exit status 1 at the end).
"""
from __future__ import annotations

import argparse
import importlib
import json
import sys
import time
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import common  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="shorter runs (a smoke test of the benchmarks)")
    p.add_argument("--full", action="store_true", help="also run the slow reference integrators over 2000 years (hours)")
    p.add_argument("--only", action="append", default=[], help="run only sections whose title or module contains WORD")
    p.add_argument("--json", help="write the sections' results to this JSON file")
    args = p.parse_args(argv)
    for path in sorted(HERE.glob("*.py")):
        if path.stem in ("run", "common") or path.stem.startswith("_"):
            continue
        importlib.import_module(path.stem)
    ctx = common.Context(quick=args.quick, full=args.full)
    ctx.print("tumble_ros benchmarks" + (" (quick)" if args.quick else " (full)" if args.full else ""))
    for line in common.machine_description():
        ctx.print(line)
    failed = []
    for order, title, fn in sorted(common.SECTIONS, key=lambda s: (s[0], s[1])):
        if args.only and not any(w.lower() in (title + " " + fn.__module__).lower() for w in args.only):
            continue
        ctx.print(f"\n== {title} ==")
        start = time.perf_counter()
        try:
            result = fn(ctx)
        except Exception:  # report and go on with the other sections
            traceback.print_exc()
            failed.append(title)
            continue
        if result is not None:
            ctx.results[title] = result
        ctx.print(f"  (section took {time.perf_counter() - start:.0f} s)")
    if args.json:
        Path(args.json).write_text(json.dumps(ctx.results, indent=2, default=str))
    if failed:
        ctx.print(f"\nfailed sections: {', '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
