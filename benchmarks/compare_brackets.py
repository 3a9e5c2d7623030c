"""Check that two runs of a study agree within their certificates (clearance engine changes, issue 13).

    python benchmarks/compare_brackets.py BEFORE_DIR AFTER_DIR [STUDY ...]

For every pair of certified values found in both runs -- JSON objects holding ``X`` and
``X_upper`` side by side (``p_max``/``p_upper``, ``p_max_mm``/``p_upper_mm``, ...; arrays or
numbers) and the columns ``p_max_mm``/``p_upper_mm``, ``r_max_deg``/``r_upper_deg`` of the entry
tables (``NAME_entries.csv``) -- the brackets ``[value, upper]`` of the two runs must overlap:
``value_a <= upper_b`` and ``value_b <= upper_a`` (relative slack 1e-12). Prints, per study, the
number of brackets compared, how many fail to overlap, and the largest relative change of the
attained values. Values without an upper bound beside them are not judged here
(``compare_study_json.py`` lists them).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

PAIRS = (("p_max", "p_upper"), ("r_max", "r_upper"), ("p_max_mm", "p_upper_mm"), ("r_max_rad", "r_upper_rad"),
         ("r_max_deg", "r_upper_deg"), ("multistart_p_mm", None))


def _brackets(d, path=""):
    """Yield (path, value array, upper array) for every certified pair in a JSON tree."""
    if isinstance(d, dict):
        for v, u in PAIRS:
            if u and v in d and u in d:
                try:
                    yield f"{path}/{v}", np.asarray(d[v], float), np.asarray(d[u], float)
                except (TypeError, ValueError):
                    pass
        for k, x in d.items():
            yield from _brackets(x, f"{path}/{k}")
    elif isinstance(d, list):
        for i, x in enumerate(d):
            if isinstance(x, (dict, list)):
                yield from _brackets(x, f"{path}/{i}")


def compare(before: Path, after: Path, name: str) -> dict:
    a = dict((p, (v, u)) for p, v, u in _brackets(json.loads((before / f"{name}.json").read_text())))
    b = dict((p, (v, u)) for p, v, u in _brackets(json.loads((after / f"{name}.json").read_text())))
    pairs = [(p, a[p], b[p]) for p in a if p in b and a[p][0].shape == b[p][0].shape]
    ta, tb = before / f"{name}_entries.csv", after / f"{name}_entries.csv"
    if ta.exists() and tb.exists():
        import pandas as pd

        ea, eb = pd.read_csv(ta), pd.read_csv(tb)
        for v, u in (("p_max_mm", "p_upper_mm"), ("r_max_deg", "r_upper_deg")):
            if {v, u} <= set(ea) and {v, u} <= set(eb) and len(ea) == len(eb):
                pairs.append((f"entries/{v}", (ea[v].to_numpy(float), ea[u].to_numpy(float)),
                              (eb[v].to_numpy(float), eb[u].to_numpy(float))))
    n = bad = 0
    change = 0.0
    for p, (va, ua), (vb, ub) in pairs:
        ok = (va <= ub * (1 + 1e-12) + 1e-300) & (vb <= ua * (1 + 1e-12) + 1e-300)
        n += ok.size
        bad += int((~ok).sum())
        with np.errstate(all="ignore"):
            rel = np.abs(va - vb) / np.maximum(np.abs(va), 1e-300)
        change = max(change, float(np.nanmax(rel)) if rel.size else 0.0)
        if not ok.all():
            print(f"  no overlap: {name}{p} at {np.flatnonzero(~ok.ravel())[:5].tolist()}")
    return {"brackets": n, "not_overlapping": bad, "largest_relative_change": change}


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 2:
        print(__doc__)
        return 2
    before, after = Path(argv[0]), Path(argv[1])
    names = argv[2:] or sorted(p.stem for p in before.glob("*.json") if (after / p.name).exists())
    worst = 0
    for name in names:
        r = compare(before, after, name)
        worst += r["not_overlapping"]
        print(f"{name}: {r['brackets']} brackets compared, {r['not_overlapping']} do not overlap, "
              f"largest relative change of an attained value {r['largest_relative_change']:.2e}")
    return 1 if worst else 0


if __name__ == "__main__":
    sys.exit(main())
