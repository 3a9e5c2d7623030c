"""Stack allocation benchmark (issue 43 item 4): the ``[stack.allocation]`` optimum of a generated stack
study with 1 000 / 2 000 / 5 000 dimensions, worst case (centred and asymmetric zones, reciprocal and
exponential costs) and RSS (centred zones). Prints, per size, the seconds of reading the table and
building the problem, of the optimum (the dual search, evotol/allocators/stack_dual.py) and of the
whole ``evotol run`` in a subprocess (JSON and page included), with the certificate's gap and KKT
residual; the lines ``N dimensions: optimum X s`` (worst case, centred, reciprocal) and ``N dimensions: rss
refusal after X s`` (an RSS optimum of asymmetric zones, from the read table to the one-line error) are
the ones benchmarks/run_all.py puts beside issue 43's targets (5 000 dimensions: optimum <= 2 s; the
refusal before any work). With ``--slsqp N`` it also times the cutting-plane SLSQP path on the
N-dimension stacks and prints the relative cost difference.

    python benchmarks/bench_stack.py [--sizes 1000 2000 5000] [--slsqp 1000]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import evotol.allocators.optimum as optimum  # noqa: E402
from evotol.errors import ValidationError  # noqa: E402
from evotol.studyfile.stack_table import allocation_from_table, stack_from_table  # noqa: E402

COSTS = {"reciprocal": {"model": "reciprocal", "a0": 1.0, "a1": 0.5, "scale": 1e-5},
         "exponential": {"model": "exponential", "a0": 5.0, "a1": 0.2, "scale": 1e-5}}


def stack_table(n: int, cost: str, measure: str = "worst_case", asymmetric: bool = False) -> dict:
    """A ``[stack]`` table of n dimensions (mm), limits ±60 % of the drawn worst case (or twice the RSS)."""
    rng = np.random.default_rng(n)
    a = rng.choice([-1.0, 1.0], n) * rng.uniform(0.5, 2.0, n)
    nom, tol = rng.uniform(1, 20, n), rng.uniform(0.01, 0.05, n)
    g0 = float(a @ nom)
    half = 0.6 * float(np.abs(a) @ tol) if measure == "worst_case" else 2.0 * float(np.sqrt(np.sum((a * tol) ** 2)))
    dims = {}
    for i in range(n):
        d = {"nominal": float(nom[i]), "sensitivity": float(a[i])}
        if asymmetric and i % 3 == 0:
            d.update(upper=float(tol[i]), lower=0.0)
        else:
            d["tolerance"] = float(tol[i])
        dims[f"d{i}"] = d
    lim = {"lower_limit": g0 - half, "upper_limit": g0 + half} if measure == "worst_case" else {}
    return {"gap": "gap", "unit": "m" if measure == "rss" else "mm", **lim, "dimensions": dims,
            "allocation": {"measure": measure, "lower": 0.001, "upper": 0.2, "cost": COSTS[cost],
                           "methods": {"optimum": {}}}}


def rss_centred(table: dict) -> dict:
    """The RSS table with limits exactly centred on the nominal gap (metres: no unit conversion)."""
    dims = {k: {**v, "nominal": 0.0, "tolerance": v["tolerance"] * 1e-3} for k, v in table["dimensions"].items()}
    a = np.array([v["sensitivity"] for v in dims.values()])
    h = np.array([v["tolerance"] for v in dims.values()])
    half = 2.0 * float(np.sqrt(np.sum((a * h) ** 2)))
    al = {**table["allocation"], "lower": 1e-6, "upper": 2e-4}
    return {**table, "dimensions": dims, "lower_limit": -half, "upper_limit": half, "allocation": al}


def toml_of(name: str, table: dict) -> str:
    lines = [f'name = "{name}"', "[stack]"]
    for k, v in table.items():
        if k not in ("dimensions", "allocation"):
            lines.append(f"{k} = {v!r}" if not isinstance(v, str) else f'{k} = "{v}"')
    al = table["allocation"]
    lines += ["[stack.allocation]", f'measure = "{al["measure"]}"', f"lower = {al['lower']!r}", f"upper = {al['upper']!r}",
              "cost = { " + ", ".join(f'{k} = "{v}"' if isinstance(v, str) else f"{k} = {v!r}" for k, v in al["cost"].items()) + " }",
              "methods = { optimum = {} }"]
    for name_, d in table["dimensions"].items():
        lines.append(f"[stack.dimensions.{name_}]")
        lines += [f"{k} = {v!r}" for k, v in d.items()]
    return "\n".join(lines) + "\n"


def one(n: int, cost: str, measure: str, asymmetric: bool, slsqp: bool, tmp: Path) -> None:
    table = stack_table(n, cost, measure, asymmetric)
    if measure == "rss":
        table = rss_centred(table)
    label = f"{n:5d} {cost:11s} {measure:10s} {'asymmetric' if asymmetric else 'centred':10s}"
    t0 = time.perf_counter()
    stack, _, display = stack_from_table(table)
    problem, _ = allocation_from_table(table, stack, display["scale"])
    t1 = time.perf_counter()
    r = optimum.allocate_optimum(problem)
    t2 = time.perf_counter()
    path = tmp / f"stack_{n}_{cost}_{measure}_{int(asymmetric)}.toml"
    path.write_text(toml_of(path.stem, table))
    t3 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "evotol.cli", "-q", "run", str(path), "--out", str(tmp / path.stem)],
                   cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
    t4 = time.perf_counter()
    c = r.certificate
    line = (f"{label} set-up {t1 - t0:6.2f} s  optimum {t2 - t1:6.2f} s  evotol run {t4 - t3:6.2f} s  "
            f"cost {r.cost:.10g}  gap {c['gap']:.1e}  KKT {c['kkt_residual']:.1e}  {'ok' if t2 - t1 <= 2 else 'OVER'} (<= 2 s)")
    if slsqp:
        keep, optimum.stack_rows = optimum.stack_rows, lambda p: None
        try:
            t5 = time.perf_counter()
            old = optimum.allocate_optimum(problem)
            line += f"  | SLSQP {time.perf_counter() - t5:6.2f} s, cost rel. diff {(r.cost - old.cost) / old.cost:.1e}"
        finally:
            optimum.stack_rows = keep
    print(line, flush=True)
    if measure == "worst_case" and cost == "reciprocal" and not asymmetric:
        print(f"  {n} dimensions: optimum {t2 - t1:.3f} s", flush=True)       # the line run_all.py reads


def rss_refusal(n: int) -> None:
    """The refusal of an RSS optimum of asymmetric zones: seconds from the read table to the one-line error."""
    table = stack_table(n, "reciprocal", "worst_case", True)
    table["allocation"] = {**table["allocation"], "measure": "rss"}
    stack, _, display = stack_from_table(table)
    t0 = time.perf_counter()
    try:
        allocation_from_table(table, stack, display["scale"])
    except ValidationError as exc:
        print(f"  {n} dimensions: rss refusal after {time.perf_counter() - t0:.3f} s ({exc.field})", flush=True)
    else:
        print(f"  {n} dimensions: rss of asymmetric zones NOT refused", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000, 5000])
    ap.add_argument("--slsqp", type=int, nargs="*", default=[], help="sizes at which SLSQP is timed too")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            for cost, measure, asym in (("reciprocal", "worst_case", False), ("exponential", "worst_case", False),
                                        ("reciprocal", "worst_case", True), ("reciprocal", "rss", False)):
                one(n, cost, measure, asym, n in args.slsqp, Path(tmp))
            rss_refusal(n)


if __name__ == "__main__":
    main()
