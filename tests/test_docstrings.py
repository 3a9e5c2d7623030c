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

A contract is documented once (issue 32 item 3), and the audit counts it where it is written:

- a method that overrides a documented method of a base class (a measure's ``evaluate``, a cost
  model's ``cost``, a robot's ``sensitivity``) needs no docstring (``inspect.getdoc``, ``help``
  and the site show the base's) or a short one that says what differs; parameters, ``Returns``
  and ``Raises`` the base documents count as documented;
- a class that keeps its base's constructor (a cost model) may leave the constructor's
  parameters to the base's docstring;
- a parameter that several definitions of a module or package share may be described once, in a
  ``Parameters`` section of the module's (or an enclosing package's) docstring
  (:func:`shared_parameters`); a definition's own entry wins.

``tests/docstring_counts.py`` counts how many ``Parameters`` entries are still repeated verbatim;
:func:`test_repeated_parameter_entries_at_most_half_of_the_issue` holds it to half the issue's 533.

Every public module has its page in the API reference (``docs/api/<module>.rst``), and the site
built from them is checked by CI with ``sphinx -W``.

Run as a script to list what a module (or package, with its submodules) lacks::

    python tests/test_docstrings.py evotol.robots.delta evotol.measures
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

if __name__ == "__main__":      # run as a script: this checkout's packages, not an installed copy
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import evotol  # noqa: E402
from tests.docstring_rules import PACKAGES, _doc_sections, _entries, documented_base, shared_parameters

ROOT = Path(__file__).resolve().parents[1]
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


def _validator(shared: dict, base_returns: list, base_yields: list):
    """numpydoc's validator, told the parameters documented elsewhere (the base's, the module's)
    and the ``Returns`` / ``Yields`` of the base (an override states only what differs)."""
    import numpydoc.validate

    class Validator(numpydoc.validate.Validator):
        def __init__(self, obj_name):
            super().__init__(numpydoc.validate.get_doc_object(self._load_obj(obj_name)))

        @property
        def doc_all_parameters(self):
            own = super().doc_all_parameters
            taken = set(self.signature_parameters)
            return {**own, **{n: e for n, e in shared.items() if n in taken and n not in own}}

        @property
        def returns(self):
            return super().returns or base_returns

        @property
        def yields(self):
            return super().yields or base_yields

    return Validator


def audit(path: str, obj, kind: str) -> list[str]:
    """What one public definition lacks (empty when its docstring is complete), one line each.

    A contract is documented once: a method overriding a documented method of a base class (a
    measure's ``evaluate``, a cost model's ``cost``) needs no docstring of its own, or a short one
    saying what differs; its parameters, ``Returns`` and ``Raises`` may be the base's. A class that
    keeps its base's constructor may leave the constructor's parameters to the base. A parameter
    described in its module's (or package's) docstring needs no entry (:func:`shared_parameters`).
    """
    import numpydoc.validate

    base = documented_base(path, obj, kind)
    own_doc = (obj.__doc__ or "").strip()
    if kind == "property" or (inspect.isclass(obj) and issubclass(obj, BaseException) and "__init__" not in vars(obj)):
        return [] if own_doc or base is not None else ["GL08 no docstring"]
    if kind == "class":
        raising = [m for m in ("__init__", "__post_init__") if m in vars(obj) and _raises_itself(vars(obj)[m])]
    else:
        raising = [obj] if _raises_itself(obj) else []
    base_sections = _sections(base) if base is not None else set()
    lacks_raises = bool(raising) and "Raises" not in _sections(obj) | base_sections
    if not own_doc and base is not None:      # inherited whole (inspect.getdoc, help and the site show it)
        return ["RA01 the body raises, but neither it nor its base has a Raises section"] if lacks_raises else []
    base_doc = _doc_sections(base.__doc__) if base is not None else None
    shared = {**shared_parameters(obj.__module__), **(_entries(base.__doc__) if base is not None else {})}
    result = numpydoc.validate.validate(path, validator_cls=_validator(
        shared, base_doc["Returns"] if base_doc else [], base_doc["Yields"] if base_doc else []))
    problems = [f"{code} {message}" for code, message in result["errors"] if code in CODES]
    if lacks_raises:
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


def test_audit_accepts_a_contract_documented_once():
    """The audit's inheritance rules: an override of a documented base method needs no docstring
    (or a one-line one), a parameter described in the module docstring needs no entry; but an
    override of an undocumented method, and a parameter described nowhere, are still found."""
    pytest.importorskip("numpydoc")
    from tests import toy_robot

    class Base:
        """A protocol."""

        def run(self, x):
            """Run once.

            Parameters
            ----------
            x : float
                A length (m).

            Returns
            -------
            float
                The result (m).
            """
            return x

        def bare(self, x):
            return x

    class Impl(Base):
        """An implementation."""

        def run(self, x):
            return 2 * x

        def bare(self, x):
            return 3 * x

    class Short(Base):
        """Another one."""

        def run(self, x):
            """Twice the base's result."""
            return 2 * x

    def shared(gap, other):
        """Use the module's ``gap``; ``other`` is described nowhere."""

    def shared_ok(gap):
        """Use the module's ``gap``."""

    saved = toy_robot.__doc__
    for obj in (Base, Impl, Short, shared, shared_ok):
        obj.__module__ = toy_robot.__name__
        obj.__qualname__ = obj.__name__
        setattr(toy_robot, obj.__name__, obj)
    for cls in (Base, Impl, Short):
        for f in vars(cls).values():
            if inspect.isfunction(f):
                f.__module__, f.__qualname__ = toy_robot.__name__, f"{cls.__name__}.{f.__name__}"
    toy_robot.__doc__ = (saved or "") + "\n\nParameters\n----------\ngap : float\n    A gap (m).\n"
    shared_parameters.cache_clear()
    try:
        got = {name: audit(f"{toy_robot.__name__}.{name}", obj, kind) for name, obj, kind in [
            ("Impl.run", Impl.run, "method"), ("Short.run", Short.run, "method"),
            ("Impl.bare", Impl.bare, "method"), ("shared", shared, "function"),
            ("shared_ok", shared_ok, "function")]}
    finally:
        toy_robot.__doc__ = saved
        shared_parameters.cache_clear()
        for name in ("Base", "Impl", "Short", "shared", "shared_ok"):
            delattr(toy_robot, name)
    assert got["Impl.run"] == [] and got["Short.run"] == [] and got["shared_ok"] == [], got
    assert [p[:4] for p in got["Impl.bare"]] == ["GL08"], got
    assert [p[:4] for p in got["shared"]] == ["PR01"] and "other" in got["shared"][0] and "gap" not in got["shared"][0], got


def test_repeated_parameter_entries_at_most_half_of_the_issue():
    """Issue 32 item 3: 533 of 2 267 ``Parameters`` entries were repeated verbatim (main
    ``f4696af``, counted by ``tests/docstring_counts.py``); documented once, at most half remain."""
    from tests.docstring_counts import count

    found = count(ROOT)
    assert found["repeated"] <= 533 // 2, f"{found['repeated']} of {found['entries']} entries repeated verbatim"


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
