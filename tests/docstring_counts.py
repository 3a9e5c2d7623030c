"""How much of the source is prose, and how much of the prose is repeated (issue 32 item 3).

Counts, over the ``.py`` files of ``evotol``, ``robots`` and ``cost_models``:

- the lines, the lines of docstrings (module, class and function docstrings, from ``ast``) and the
  lines of code (:func:`code_lines`: neither docstring, comment nor blank -- the count the module
  size rule of ``tests/test_layers.py`` uses);
- the numpydoc ``Parameters`` entries (``name : type`` and its description) of every docstring,
  and how many of them are *repeated*: their text, with whitespace normalised (a re-wrapped copy
  is still a copy), appears in another entry too.

The issue measured 533 repeated entries of 2 267 on main ``f4696af``; ``test_docstrings.py``
holds the count to at most half of that. Run on one or more checkouts::

    python tests/docstring_counts.py [ROOT ...]          # default: this checkout
    python tests/docstring_counts.py --list [ROOT]       # also every repeated entry and where
"""
from __future__ import annotations

import ast
import io
import re
import sys
import tokenize
from collections import Counter, defaultdict
from pathlib import Path

PACKAGES = ("evotol", "robots", "cost_models")
_DASHES = re.compile(r"^\s*-{3,}\s*$")


def source_files(root: Path) -> list[Path]:
    """The ``.py`` files of the three packages under ``root``."""
    return sorted(p for pkg in PACKAGES for p in (Path(root) / pkg).rglob("*.py"))


def _docstring_nodes(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str):
                yield node, first


def docstring_line_numbers(source: str) -> set[int]:
    """1-based numbers of the lines that belong to a docstring of ``source``."""
    return {n for _, expr in _docstring_nodes(ast.parse(source)) for n in range(expr.lineno, expr.end_lineno + 1)}


def code_lines(source: str) -> int:
    """Lines of ``source`` that hold code: not blank, not only a comment, not part of a docstring."""
    doc = docstring_line_numbers(source)
    code = set()
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type in (tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT,
                        tokenize.ENDMARKER):
            continue
        code.update(n for n in range(tok.start[0], tok.end[0] + 1) if n not in doc)
    return len(code)


def parameter_entries(doc: str) -> list[str]:
    """The entries of the ``Parameters`` / ``Other Parameters`` sections of a cleaned docstring,
    each as its text with whitespace normalised (``"t : float Tolerance (m)."``)."""
    lines = doc.expandtabs().splitlines()
    out: list[list[str]] = []
    i = 0
    while i < len(lines) - 1:
        if lines[i].strip() in ("Parameters", "Other Parameters") and _DASHES.match(lines[i + 1]):
            indent = len(lines[i]) - len(lines[i].lstrip())
            i += 2
            while i < len(lines):
                line = lines[i]
                if line.strip():
                    level = len(line) - len(line.lstrip())
                    if level < indent or (level == indent and i + 1 < len(lines) and _DASHES.match(lines[i + 1])):
                        break
                    if level == indent:
                        out.append([])
                    if out:
                        out[-1].append(line.strip())
                i += 1
            continue
        i += 1
    return [" ".join(" ".join(e).split()) for e in out]


def count(root: Path) -> dict:
    """Line and ``Parameters`` counts of the checkout at ``root`` (see the module docstring)."""
    lines = doc_lines = code = 0
    entries: list[tuple[str, str]] = []
    for path in source_files(root):
        source = path.read_text()
        lines += len(source.splitlines())
        code += code_lines(source)
        tree = ast.parse(source)
        for node, expr in _docstring_nodes(tree):
            doc_lines += expr.end_lineno - expr.lineno + 1
            entries += [(str(path.relative_to(root)), e) for e in parameter_entries(ast.get_docstring(node) or "")]
    seen = Counter(e for _, e in entries)
    where = defaultdict(list)
    for f, e in entries:
        if seen[e] > 1:
            where[e].append(f)
    return {"lines": lines, "docstring_lines": doc_lines, "code_lines": code, "entries": len(entries),
            "repeated": sum(len(v) for v in where.values()), "repeated_where": dict(where)}


def main(argv: list[str]) -> None:
    listing = "--list" in argv
    roots = [a for a in argv if a != "--list"] or [str(Path(__file__).resolve().parents[1])]
    for root in roots:
        c = count(Path(root))
        print(f"{root}: {c['lines']} lines, {c['docstring_lines']} in docstrings "
              f"({100 * c['docstring_lines'] / c['lines']:.0f} %), {c['code_lines']} of code; "
              f"{c['entries']} Parameters entries, {c['repeated']} repeated verbatim elsewhere")
        if listing:
            for entry, files in sorted(c["repeated_where"].items(), key=lambda kv: -len(kv[1])):
                print(f"  {len(files)} x {entry[:100]}\n      {dict(Counter(files))}")


if __name__ == "__main__":
    main(sys.argv[1:])
