"""Numpydoc on the public API (issue 26 item 6), checked two ways.

1. The front door (``evotol.__all__``): every name a user calls carries ``Parameters`` and
   ``Raises`` (a plain value checked later: ``Raises`` on its ``validate``), every function
   ``Returns``.
2. Every public definition of ``evotol``, ``robots`` and ``cost_models`` -- a function, class,
   method or property whose name and module path have no leading ``_`` -- passes
   :func:`audit_module`: a docstring; numpydoc's own validation (``numpydoc.validate``) finds every
   parameter of the signature documented and none unknown (PR01, PR02; a class documents its
   constructor's), a ``Returns`` section where the body returns a value (RT01) and ``Yields`` where
   it yields (YD01); and a ``Raises`` section where the body raises an exception itself (a ``raise``
   statement naming one; a bare re-``raise`` does not count).

Every public module has its page in the API reference (``docs/api/<module>.rst``), and the site
built from them is checked by CI with ``sphinx -W``.

Run as a script to list what a module (or package, with its submodules) lacks::

    python tests/test_docstrings.py robots.delta evotol.measures
"""
from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import evotol

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("evotol", "robots", "cost_models")
#: numpydoc validation codes the audit enforces (numpydoc/validate.py): parameters documented (PR01)
#: and none unknown (PR02), Returns (RT01), Yields (YD01), a docstring at all (GL08)
CODES = ("GL08", "PR01", "PR02", "RT01", "YD01")

SECTION = "^ *{}\n *-{{3,}}$"

#: front-door names that are not called with arguments (errors, protocols, result records)
NOT_CALLED = {"EvotolError", "ValidationError", "KinematicsError", "ConvergenceError", "InfeasibleError",
              "RobotErrorModel", "Evaluation", "AllocationResult", "MonteCarloResult", "ParetoFront",
              "ProcessResult"}
#: plain values checked later: their ``validate`` (or the problem that holds them) raises
PLAIN_VALUES = {"Tolerance", "Requirement", "Process", "Distribution"}


def _sections(obj) -> set[str]:
    doc = inspect.getdoc(obj) or ""
    return {s for s in ("Parameters", "Returns", "Raises") if re.search(SECTION.format(s), doc, re.M)}


@pytest.mark.parametrize("name", [n for n in evotol.__all__ if n not in NOT_CALLED])
def test_front_door_numpydoc_sections(name):
    obj = getattr(evotol, name)
    need = {"Parameters", "Returns"} if inspect.isfunction(obj) else {"Parameters"}
    missing = need - _sections(obj)
    raises = obj.validate if name in PLAIN_VALUES and hasattr(obj, "validate") else obj
    if name not in PLAIN_VALUES or raises is not obj:
        missing |= {"Raises"} - _sections(raises)
    assert not missing, f"evotol.{name} ({obj.__module__}) lacks numpydoc section(s) {sorted(missing)}"


def test_section_pattern_finds_a_section_and_misses_prose():
    """The check itself: a numpydoc header is found, the word in running text is not."""
    def with_section():
        """Do.

        Parameters
        ----------
        x : float
            Length (m).
        """

    def prose():
        """Parameters are described in the module docstring; Returns nothing."""

    assert _sections(with_section) == {"Parameters"}
    assert _sections(prose) == set()


def public_modules(packages=PACKAGES) -> list[str]:
    """Dotted names of the public modules of ``packages``, the packages themselves included."""
    names = []
    for pkg in packages:
        names.append(pkg)
        for info in pkgutil.walk_packages(importlib.import_module(pkg).__path__, pkg + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                names.append(info.name)
    return names


def public_definitions(modname: str):
    """``(dotted path, object, kind)`` of every public definition of a module: its functions and
    classes (defined there, not imported), and their public methods and properties."""
    module = importlib.import_module(modname)
    for name, obj in vars(module).items():
        if name.startswith("_") or getattr(obj, "__module__", None) != modname:
            continue
        if inspect.isfunction(obj):
            yield f"{modname}.{name}", obj, "function"
        elif inspect.isclass(obj):
            yield f"{modname}.{name}", obj, "class"
            for member_name, member in vars(obj).items():
                if member_name.startswith("_"):
                    continue
                func = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
                if inspect.isfunction(func):
                    yield f"{modname}.{name}.{member_name}", func, "method"
                elif isinstance(member, property):
                    yield f"{modname}.{name}.{member_name}", member, "property"


def _raises_itself(func) -> bool:
    """True when the function's own body (not a nested function or class) has a ``raise X``."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return False
    body = tree.body[0]
    stack = list(ast.iter_child_nodes(body))
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            continue
        if isinstance(node, ast.Raise) and node.exc is not None:
            return True
        stack.extend(ast.iter_child_nodes(node))
    return False


def audit(path: str, obj, kind: str) -> list[str]:
    """What one public definition lacks (empty when its docstring is complete), one line each."""
    import numpydoc.validate

    if kind == "property":
        return [] if (obj.__doc__ or "").strip() else ["GL08 no docstring"]
    if inspect.isclass(obj) and issubclass(obj, BaseException) and "__init__" not in vars(obj):
        return [] if (obj.__doc__ or "").strip() else ["GL08 no docstring"]
    result = numpydoc.validate.validate(path)
    problems = [f"{code} {message}" for code, message in result["errors"] if code in CODES]
    if kind == "class":
        raising = [m for m in ("__init__", "__post_init__") if m in vars(obj) and _raises_itself(vars(obj)[m])]
    else:
        raising = [obj] if _raises_itself(obj) else []
    if raising and "Raises" not in _sections(obj):
        problems.append("RA01 the body raises, but there is no Raises section")
    return problems


def audit_module(modname: str) -> dict[str, list[str]]:
    """``{dotted path: problems}`` of a module's public definitions that lack something."""
    found = {}
    for path, obj, kind in public_definitions(modname):
        problems = audit(path, obj, kind)
        if problems:
            found[path] = problems
    return found


@pytest.mark.parametrize("modname", public_modules())
def test_public_definitions_numpydoc(modname):
    pytest.importorskip("numpydoc")
    lacking = audit_module(modname)
    assert not lacking, "\n".join(f"{path}: {'; '.join(p)}" for path, p in lacking.items())


def test_audit_finds_what_is_missing():
    """The audit itself: a raise without Raises, an undocumented parameter and a missing Returns
    are each found; a complete docstring passes."""
    pytest.importorskip("numpydoc")
    from tests import toy_robot  # a module of ours with a plain function to validate by path

    def incomplete(x, y):
        """Sum two lengths.

        Parameters
        ----------
        x : float
            First length (m).
        """
        if x < 0:
            raise ValueError("x")
        return x + y

    def complete(x):
        """Double a length.

        Parameters
        ----------
        x : float
            Length (m).

        Returns
        -------
        float
            Twice ``x`` (m).

        Raises
        ------
        ValueError
            When ``x`` is negative.
        """
        if x < 0:
            raise ValueError("x")
        return 2 * x

    for func in (incomplete, complete):
        func.__module__ = toy_robot.__name__
        func.__qualname__ = func.__name__
        setattr(toy_robot, func.__name__, func)
    try:
        bad = audit(f"{toy_robot.__name__}.incomplete", incomplete, "function")
        good = audit(f"{toy_robot.__name__}.complete", complete, "function")
    finally:
        del toy_robot.incomplete, toy_robot.complete
    assert sorted(p[:4] for p in bad) == ["PR01", "RA01", "RT01"], bad
    assert good == []


def test_every_public_module_has_an_api_page():
    """The API reference lists every public module (``docs/api/<module>.rst``, ``.. evotol-api::``)."""
    missing = [m for m in public_modules() if not (ROOT / "docs" / "api" / f"{m}.rst").is_file()]
    assert not missing, f"modules without a page in docs/api/: {missing}"


def test_site_builds_with_warnings_as_errors(tmp_path):
    """The docs/ pages and the API reference build with ``sphinx -W`` (as ``.ci/run`` does), so a
    docstring that is not valid reStructuredText (``|x|`` is a substitution) fails here, before it
    reaches main. Skipped without the ``docs`` extra; the dummy builder parses every page and
    docstring but writes no HTML."""
    pytest.importorskip("sphinx")
    pytest.importorskip("numpydoc")
    pytest.importorskip("myst_parser")
    docs = Path(__file__).resolve().parents[1] / "docs"
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "dummy", str(docs),
                          str(tmp_path / "site")], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-4000:]


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    wanted = sys.argv[1:] or list(PACKAGES)
    mods = [m for m in public_modules() if any(m == w or m.startswith(w + ".") for w in wanted)]
    total = 0
    for mod in mods:
        for path, problems in audit_module(mod).items():
            total += 1
            print(f"{path}: {'; '.join(problems)}")
    print(f"{total} definition(s) lacking something in {len(mods)} module(s)")
