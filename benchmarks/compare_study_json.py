"""Compare two study JSON files number by number (used to show a refactor changes no result).

    python benchmarks/compare_study_json.py BEFORE.json AFTER.json [--rtol 1e-9] [--ignore seconds ...]

Prints every number that differs beyond ``rtol`` (relative) with its JSON path, the keys only one
side has, and the count of numbers compared. Keys that are wall times (any path component
containing ``seconds``, ``speedup`` or ``timing``) are skipped by default: they are measurements
of this machine's load, not results.
"""
from __future__ import annotations

import argparse
import json
import math
import sys

TIMING = ("seconds", "speedup", "timing")


def walk(a, b, path, out, rtol, ignore):
    if any(t in str(p) for p in path for t in ignore):
        return
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b), key=str):
            if k not in a or k not in b:
                out["only"].append(("/".join(map(str, path + [k])), "before" if k in a else "after"))
            else:
                walk(a[k], b[k], path + [k], out, rtol, ignore)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out["diff"].append(("/".join(map(str, path)), f"length {len(a)} vs {len(b)}"))
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, path + [i], out, rtol, ignore)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        out["n"] += 1
        if not (a == b or (math.isfinite(a) and math.isfinite(b) and abs(a - b) <= rtol * max(abs(a), abs(b)))):
            out["diff"].append(("/".join(map(str, path)), f"{a!r} vs {b!r}"))
    else:
        out["n"] += 1
        if a != b:
            out["diff"].append(("/".join(map(str, path)), f"{a!r} vs {b!r}"[:200]))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("before")
    p.add_argument("after")
    p.add_argument("--rtol", type=float, default=1e-9)
    p.add_argument("--ignore", nargs="*", default=list(TIMING), help="skip keys containing these words")
    args = p.parse_args(argv)
    a, b = (json.load(open(f, encoding="utf-8")) for f in (args.before, args.after))
    out = {"n": 0, "diff": [], "only": []}
    walk(a, b, [], out, args.rtol, args.ignore)
    for where, what in out["diff"]:
        print(f"DIFF {where}: {what}")
    for where, side in out["only"]:
        print(f"ONLY {side}: {where}")
    print(f"{out['n']} values compared, {len(out['diff'])} differ, {len(out['only'])} keys on one side only")
    return 1 if out["diff"] else 0


if __name__ == "__main__":
    sys.exit(main())
