"""Where a contract is documented (issue 32 item 3): the rules ``tests/test_docstrings.py`` audits
and ``docs/conf.py`` renders, in one place (no pytest needed, so the site builds without it).

- :func:`documented_base`: the documented definition a method or class inherits its contract from
  (the protocol method it overrides, the base constructor it keeps);
- :func:`shared_parameters`: the parameters a module's or package's docstring describes once for
  the definitions that share them.
"""
from __future__ import annotations

import importlib
import inspect
import warnings
from functools import lru_cache

PACKAGES = ("evotol", "evotol.robots", "evotol.cost_models")


def _doc_sections(doc: str):
    """numpydoc's parse of a docstring (``inspect.cleandoc``-ed), or None when it has none."""
    from numpydoc.docscrape import NumpyDocString

    if not (doc and doc.strip()):
        return None
    with warnings.catch_warnings():     # a module docstring may have headings numpydoc does not know
        warnings.simplefilter("ignore", UserWarning)
        return NumpyDocString(inspect.cleandoc(doc))


def _entries(doc: str) -> dict[str, tuple[str, list[str]]]:
    """``{name: (type, description)}`` of a docstring's ``Parameters`` (``a, b : float`` gives both)."""
    parsed = _doc_sections(doc)
    out = {}
    for names, type_, desc in (parsed["Parameters"] + parsed["Other Parameters"]) if parsed else []:
        for name in names.split(", "):
            out[name.replace("\\", "")] = (type_, desc)
    return out


@lru_cache(maxsize=None)
def shared_parameters(modname: str) -> dict[str, tuple[str, list[str]]]:
    """Parameters documented once for a module: the ``Parameters`` section of its docstring and of
    each package above it (the nearest wins). A function of the module that takes one of them
    and does not describe it itself is documented by it (the parameter several functions share,
    written once; the module's API page shows it above them)."""
    found: dict[str, tuple[str, list[str]]] = {}
    parts = modname.split(".")
    for i in range(1, len(parts) + 1):
        found.update(_entries(importlib.import_module(".".join(parts[:i])).__doc__ or ""))
    return found


def documented_base(path: str, obj, kind: str):
    """The documented definition this one inherits its contract from, or None: for a method, the
    same method of the nearest base class that has a docstring (a protocol's ``evaluate``,
    ``cost``, ``sensitivity``); for a class that keeps its base's constructor (no ``__init__`` of
    its own), the nearest base class defining that constructor."""
    parts = path.split(".")
    for i in range(len(parts) - 1, 0, -1):      # the longest importable prefix is the module
        try:
            module = importlib.import_module(".".join(parts[:i]))
            break
        except ImportError:
            continue
    rest = ".".join(parts[i:])
    names = rest.split(".")
    if kind in ("method", "property") and len(names) == 2:
        cls, member = getattr(module, names[0]), names[1]
        for base in cls.__mro__[1:]:
            if base is object or member not in vars(base):
                continue
            found = vars(base)[member]
            found = found.__func__ if isinstance(found, (staticmethod, classmethod)) else found
            return found if (getattr(found, "__doc__", None) or "").strip() else None
    if kind == "class" and "__init__" not in vars(obj):
        for base in obj.__mro__[1:]:
            if base is not object and "__init__" in vars(base):
                return base if (base.__doc__ or "").strip() and base.__module__.split(".")[0] in PACKAGES else None
    return None
