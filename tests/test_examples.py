"""Examples that run (issue 32 item 4): every name of ``evotol.__all__`` carries a numpydoc
``Examples`` section on its own docstring (where it is defined), and each example runs here as a
doctest, with what it prints compared to what the docstring shows.

The examples use tiny problems -- a three-dimension linear stack (whose optimum has a closed form,
which the examples check), the 3-UCR robot at a few poses, shipped mechanism descriptions -- so
each takes well under a second once evotol is imported. Outputs are rounded or printed as
booleans of a stated inequality; ``+ELLIPSIS`` stands only for long messages.
"""
from __future__ import annotations

import doctest
import inspect
import re

import pytest

import evotol

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
EXAMPLES = re.compile(r"^ *Examples\n *-{3,}$", re.M)


def _doctests(name: str) -> list[doctest.DocTest]:
    obj = getattr(evotol, name)
    finder = doctest.DocTestFinder(recurse=False, exclude_empty=True)
    return finder.find(obj, f"evotol.{name}", module=False, globs={})


@pytest.mark.parametrize("name", evotol.__all__)
def test_front_door_name_has_a_running_example(name):
    """The docstring has an ``Examples`` section with at least one example, and every example
    prints what the docstring shows."""
    obj = getattr(evotol, name)
    doc = inspect.cleandoc(obj.__doc__ or "")
    assert EXAMPLES.search(doc), f"evotol.{name} ({obj.__module__}) has no Examples section"
    tests = _doctests(name)
    assert tests and tests[0].examples, f"evotol.{name}: the Examples section holds no >>> example"
    out: list[str] = []
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in tests:
        runner.run(test, out=out.append)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, "".join(out)


def test_a_wrong_example_fails():
    """The check itself: an example whose shown output differs from what it prints is a failure."""
    def wrong():
        """Add.

        Examples
        --------
        >>> 1 + 1
        3
        """

    test = doctest.DocTestFinder(recurse=False).find(wrong, "wrong", module=False, globs={})[0]
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    runner.run(test, out=lambda s: None)
    assert runner.summarize(verbose=False).failed == 1
