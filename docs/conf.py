"""Sphinx configuration: the docs/ pages (MyST Markdown) and the API reference, one site.

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (the ``docs`` extra of
pyproject.toml). Why Sphinx + numpydoc: ``docs/index.md``.

The API pages (``docs/api/*.rst``) use one directive, ``.. evotol-api:: MODULE``: it lists the
public names of MODULE (its ``__all__``; without one, the functions and classes it defines plus
the front-door names ``evotol`` loads from it) in a summary table and documents each object once,
at its defining module (``obj.__module__``), on the first page (in ``API_PAGES`` order) that lists
it; later pages link to it. So a module split (a class moving to a new module) changes no page,
and a name added to the front door is documented on the front-door page (``evotol``, last) when no
other page lists it.
"""
from __future__ import annotations

import functools
import importlib
import inspect
import os
import sys

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, ROOT)           # the checkout being documented, before any installed evotol

project = "evotol"
author = "evotol contributors"
copyright = "evotol contributors"
release = version = importlib.import_module("evotol").__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**/__pycache__"]
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
suppress_warnings = [
    # the docs/ pages point at source files of the repository (`../evotol/problem.py`), which are
    # not pages of the site; the links stay as they are written
    "myst.xref_missing",
    # illustrative snippets with "..." in ```toml / ```json fences (docs/mechanisms.md, docs/units.md)
    "misc.highlighting_failure",
]

autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"          # numpydoc's Parameters section carries the types
autosummary_generate = False        # the evotol-api directive documents, autosummary only tabulates
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

html_theme = "furo"
html_title = f"evotol {release}"

#: the API pages, in the order they claim the objects they document (docs/api/<module>.rst)
API_PAGES = [
    "evotol.core.problem", "evotol.measures", "evotol.allocators", "evotol.core.result", "evotol.verification.montecarlo", "evotol.measures.feasibility",
    "evotol.measures.statistical.distributions", "evotol.measures.clearances", "evotol.errors", "robots", "evotol.robots.base", "evotol.robots.checks",
    "evotol.robots.mechanism", "evotol.robots.assembly", "cost_models",
]


@functools.lru_cache(maxsize=None)
def public_modules() -> tuple[str, ...]:
    """Every public module of the three packages (no ``_`` in its dotted name), in import order."""
    import pkgutil
    found = []
    for pkg in ("evotol", "robots", "cost_models"):
        found.append(pkg)
        for info in pkgutil.walk_packages(importlib.import_module(pkg).__path__, pkg + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                found.append(info.name)
    return tuple(found)


# then every other public module that has its page (docs/api/<module>.rst; tests/test_docstrings.py
# checks that every public module has one), and last the front door, which documents the names no
# page above lists
API_PAGES += [m for m in public_modules() if m not in API_PAGES and m != "evotol"
              and os.path.isfile(os.path.join(os.path.dirname(__file__), "api", f"{m}.rst"))] + ["evotol"]


def _front_door() -> dict[str, str]:
    return dict(importlib.import_module("evotol")._WHERE)


def public_names(modname: str) -> list[str]:
    """Public names of a module: ``__all__``, else what it defines plus the front-door names it serves."""
    module = importlib.import_module(modname)
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n, obj in vars(module).items()
                 if not n.startswith("_") and (inspect.isfunction(obj) or inspect.isclass(obj))
                 and getattr(obj, "__module__", None) == modname]
        names += [n for n, where in _front_door().items() if where == modname and n not in names]
    # a module listed in __all__ (``evotol.measures.feasibility.measures``) is not an API object
    return [n for n in names if not inspect.ismodule(getattr(module, n))]


def home(modname: str, name: str) -> tuple[str, str]:
    """(``module.qualname`` where the object is defined, autodoc directive) of a public name."""
    obj = getattr(importlib.import_module(modname), name)
    if inspect.isclass(obj):
        kind = "autoexception" if issubclass(obj, BaseException) else "autoclass"
    elif inspect.isfunction(obj) or inspect.isbuiltin(obj):
        kind = "autofunction"
    else:                            # a constant: documented at the module that assigns it
        return f"{_assigned_in(modname, name, obj)}.{name}", "autodata"
    return f"{obj.__module__}.{obj.__qualname__}", kind


def _assigned_in(modname: str, name: str, obj) -> str:
    """The module that assigns a constant with its ``#:`` comment: ``modname`` itself or, for a
    module re-exporting it, the public module holding the same object (else ``modname``)."""
    from sphinx.pycode import ModuleAnalyzer

    for cand in (modname, *public_modules()):
        try:
            if getattr(importlib.import_module(cand), name, None) is obj and \
                    ("", name) in ModuleAnalyzer.for_module(cand).find_attr_docs():
                return cand
        except Exception:            # a module that cannot be analysed is simply not the home
            continue
    return modname


@functools.lru_cache(maxsize=None)
def claims() -> dict[str, str]:
    """Defining path -> the API page (module name) that documents it: the first page listing it.

    Computed once per build (every page's directive reads it; it walks every page's names)."""
    owner: dict[str, str] = {}
    for page in API_PAGES:
        for name in public_names(page):
            owner.setdefault(home(page, name)[0], page)
    return owner


def _inherited_option(path: str) -> list[str]:
    """``:inherited-members:`` for a class assembled from mixins (``ToleranceProblem`` from
    ``evotol.core.problem.costs.ProblemCosts`` ...): its page lists the mixins' methods as its own, as a
    user calls them. A mixin here: a direct base from another module of the class's own subpackage,
    with no base but ``object``, no ``__init__`` and no other subclass (a shared base such as
    ``Measure`` is not one). Members of other bases (``RobotErrorModel``,
    ``object``) stay on their own pages."""
    modname, _, qualname = path.rpartition(".")
    cls = getattr(importlib.import_module(modname), qualname)
    package = cls.__module__.rpartition(".")[0]
    mixins = [b for b in cls.__bases__ if "." in package and b.__module__ != cls.__module__
              and b.__module__.rpartition(".")[0] == package and b.__bases__ == (object,) and "__init__" not in vars(b)
              and b.__subclasses__() == [cls]]
    if not mixins:
        return []
    others = [b.__name__ for b in cls.__mro__[1:] if b not in mixins]
    return [f"   :inherited-members: {', '.join(others)}"]


class EvotolAPI(SphinxDirective):
    """``.. evotol-api:: MODULE``: summary table + autodoc of the objects this page owns."""

    required_arguments = 1

    def run(self):
        modname = self.arguments[0]
        owner = claims()
        lines = [f".. automodule:: {modname}", "",
                 # the table names objects by their full defining path: no current module for it
                 ".. currentmodule:: None", "", ".. autosummary::", ""]
        entries = []
        for name in public_names(modname):
            path, kind = home(modname, name)
            lines.append(f"   ~{path}")
            if owner.get(path) == modname:
                entries.append((path, kind))
        lines.append("")
        for path, kind in entries:
            lines += [f".. {kind}:: {path}"]
            if kind in ("autoclass", "autoexception"):
                lines += ["   :members:"] + _inherited_option(path)
            lines.append("")
        node = nodes.container()
        self.state.nested_parse(StringList(lines, source=f"<evotol-api {modname}>"), self.content_offset, node)
        return node.children


def _documented_elsewhere(app, what, name, obj, options, lines):
    """Show a definition's whole contract on its page: the parameters (and ``Returns``) it leaves
    to a shared description -- the protocol method it overrides or the base constructor it keeps,
    and the ``Parameters`` of its module's or package's docstring -- are added to its docstring
    before numpydoc renders it, by the rules ``tests/test_docstrings.py`` audits
    (``tests/docstring_rules.py``)."""
    if what not in ("function", "method", "class") or not lines:
        return
    from tests.docstring_rules import _doc_sections, _entries, documented_base, shared_parameters

    try:
        signature = inspect.signature(obj)
    except (TypeError, ValueError):
        return
    stars = {inspect.Parameter.VAR_POSITIONAL: "*", inspect.Parameter.VAR_KEYWORD: "**"}
    taken = [stars.get(p.kind, "") + p.name for p in signature.parameters.values() if p.name not in ("self", "cls")]
    own = _doc_sections("\n".join(lines))
    mine = _entries("\n".join(lines))
    try:
        base = documented_base(name, obj, "class" if what == "class" else "method" if what == "method" else "function")
    except Exception:                # a name autodoc reached another way: no base to show
        base = None
    elsewhere = {**shared_parameters(getattr(obj, "__module__", "") or name.rpartition(".")[0]),
                 **(_entries(base.__doc__) if base is not None else {})}
    missing = [p for p in taken if p not in mine and p in elsewhere]
    entries: list[str] = []
    while missing:                   # ``r1, r2, r3 : float`` described together stay together
        group = [p for p in missing if elsewhere[p] == elsewhere[missing[0]]]
        missing = [p for p in missing if p not in group]
        type_, desc = elsewhere[group[0]]
        entries += [f"{', '.join(group)} : {type_}" if type_ else ", ".join(group)] + [f"    {d}" if d else "" for d in desc]
    if entries:
        at = next((i for i in range(len(lines) - 1) if lines[i].strip() == "Parameters"
                   and set(lines[i + 1].strip()) == {"-"}), None)
        if at is None:
            lines += ["", "Parameters", "----------"] + entries
        else:                        # after the section's last entry (numpydoc orders the sections)
            end = next((i for i in range(at + 2, len(lines) - 1)
                        if lines[i].strip() and not lines[i].startswith(" ") and set(lines[i + 1].strip()) == {"-"}),
                       len(lines))
            while end > at + 2 and not lines[end - 1].strip():
                end -= 1
            lines[end:end] = entries
    base_doc = _doc_sections(base.__doc__) if base is not None else None
    if base_doc is not None and what != "class" and not (own and own["Returns"]) and base_doc["Returns"]:
        lines += ["", "Returns", "-------"]
        for ret in base_doc["Returns"]:
            lines += [f"{ret.name} : {ret.type}" if ret.name else ret.type] + [f"    {d}" if d else "" for d in ret.desc]


def setup(app):
    app.add_directive("evotol-api", EvotolAPI)
    # before numpydoc's own handler (priority 500), which parses the sections
    app.connect("autodoc-process-docstring", _documented_elsewhere, priority=400)
    return {"parallel_read_safe": True}
