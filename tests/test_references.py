"""Every Sphinx cross-reference in the docstrings names something that exists.

The docstrings of ``rockfall_design/`` and of the built-in plugins'
package point at each other with ``:mod:``, ``:func:``, ``:class:``,
``:meth:``, ``:attr:`` and ``:data:`` roles. A rename leaves such a
reference behind, naming nothing; a reader (and Sphinx) then finds no
target. This test reads the docstrings from the syntax trees (module,
class and function docstrings, and the string that documents an
assignment), and resolves each target by importing it: the longest
importable module prefix, then ``getattr`` along the rest.

Names are looked up as the Python domain of Sphinx looks them up: a
leading ``~`` only shortens what is shown and is dropped; a name is tried
as written, then inside the enclosing class, then inside the module, and
a name starting with ``.`` is tried inside the enclosing class, the
module, and the package the module is in (not further up: ``.run`` in
``calibration/`` must not find the package's ``run/`` room). Two additions stand in for what
Sphinx finds elsewhere: a name the module imports (at its top, or for type
checking only) means what it imports, and the built-in names of Python
(``OSError``, ``open``) resolve, as they do through Python's own inventory.

References
----------
Sphinx, "The Python Domain: Cross-referencing Python objects",
https://www.sphinx-doc.org/en/master/usage/domains/python.html
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import re
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Source folders whose docstrings are checked, each with the folder its
#: dotted module names are taken relative to.
SOURCES = [
    (ROOT / "rockfall_design", ROOT),
    (ROOT / "plugins" / "rockfall_design_builtins", ROOT / "plugins"),
]
ROLES = ("mod", "func", "class", "meth", "attr", "data")
#: ``:role:`target``` or ``:role:`shown text <target>```.
REFERENCE = re.compile(r":(?:py:)?(" + "|".join(ROLES) + r"):`([^`]+)`")


def _module_name(path: Path, base: Path) -> str:
    parts = list(path.relative_to(base).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _docstrings(tree: ast.Module) -> Iterator[tuple[str, int, str]]:
    """Yield (enclosing class qualified name or "", first line, docstring)."""

    def walk(body: list[ast.stmt], scope: str) -> Iterator[tuple[str, int, str]]:
        for node in body:
            if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) \
                    and isinstance(node.value.value, str):
                # The module's, a class's or an assignment's docstring.
                yield scope, node.lineno, node.value.value
            elif isinstance(node, ast.ClassDef):
                yield from walk(node.body, f"{scope}.{node.name}" if scope else node.name)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                doc = ast.get_docstring(node, clean=False)
                if doc:
                    yield scope, node.body[0].lineno, doc

    yield from walk(tree.body, "")


def _imported(tree: ast.Module, module: str, is_package: bool) -> dict[str, str]:
    """Names a module imports at its top (``if TYPE_CHECKING:`` included) -> full names."""
    here = module if is_package else module.rpartition(".")[0]
    out = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.col_offset <= 4:
            base = node.module or ""
            if node.level:
                anchor = here.split(".")[: len(here.split(".")) - (node.level - 1)]
                base = ".".join(anchor + ([node.module] if node.module else []))
            out |= {a.asname or a.name: f"{base}.{a.name}" for a in node.names}
    return out


def references() -> Iterator[tuple[str, int, str, str, str, dict[str, str]]]:
    """Yield (file, line, module, enclosing class, target, imports) for every reference."""
    for folder, base in SOURCES:
        for path in sorted(folder.rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            module = _module_name(path, base)
            tree = ast.parse(text, str(path))
            imports = _imported(tree, module, path.name == "__init__.py")
            for scope, first, doc in _docstrings(tree):
                for match in REFERENCE.finditer(doc):
                    target = match.group(2)
                    inner = re.search(r"<([^>]+)>$", target)
                    target = (inner.group(1) if inner else target).strip().lstrip("~")
                    line = first + doc[: match.start()].count("\n")
                    yield (str(path.relative_to(ROOT)), line, module, scope,
                           target.removesuffix("()"), imports)


def _import(dotted: str) -> bool:
    """True if ``dotted`` names a module, or an object reached from one by getattr."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for i, name in enumerate(parts[cut:]):
            if hasattr(obj, name):
                obj = getattr(obj, name)
            elif i == len(parts) - cut - 1 and _declared_field(obj, name):
                return True
            else:
                return False
        return True
    return False


def _declared_field(owner: object, name: str) -> bool:
    """True if ``name`` is a declared field of class ``owner`` without a class value.

    Dataclass fields, annotated attributes without a default and attributes
    the class's code sets on ``self`` exist on instances only; ``getattr`` on
    the class does not find them.
    """
    if not isinstance(owner, type):
        return False
    if dataclasses.is_dataclass(owner) and name in {f.name for f in dataclasses.fields(owner)}:
        return True
    if any(name in getattr(k, "__annotations__", {}) for k in owner.__mro__):
        return True
    # An attribute set on the instance by the class's own code (``self.name = ...``).
    try:
        source = inspect.getsource(owner)
    except (OSError, TypeError):
        return False
    return re.search(rf"\bself\.{re.escape(name)}\s*(:[^=\n]*)?=", source) is not None


def _is_package(module: str) -> bool:
    try:
        return hasattr(importlib.import_module(module), "__path__")
    except ImportError:
        return False


def candidates(module: str, scope: str, target: str,
               imports: dict[str, str] | None = None) -> list[str]:
    """The full names ``target`` may mean, written in ``scope`` of ``module``."""
    inner = [f"{module}.{scope}"] if scope else []
    if target.startswith("."):
        name = target[1:]
        package = module if _is_package(module) else module.rpartition(".")[0]
        return [f"{p}.{name}" for p in [*inner, module, package] if p]
    first, dot, rest = target.partition(".")
    imported = [f"{imports[first]}{dot}{rest}"] if imports and first in imports else []
    return [target, *(f"{p}.{target}" for p in [*inner, module]), *imported,
            f"builtins.{target}"]


def test_every_reference_resolves() -> None:
    seen: dict[tuple[str, str, str], bool] = {}
    unresolved = []
    total = 0
    for file, line, module, scope, target, imports in references():
        total += 1
        key = (module, scope, target)
        if key not in seen:
            seen[key] = any(_import(c) for c in candidates(module, scope, target, imports))
        if not seen[key]:
            unresolved.append(f"{file}:{line}: {target}")
    assert total > 100, f"only {total} references found: is the pattern right?"
    assert not unresolved, (f"{len(unresolved)} of {total} references do not resolve:\n"
                            + "\n".join(unresolved))


def test_candidates_follow_sphinx_lookup() -> None:
    assert candidates("a.b.c", "K", ".f") == ["a.b.c.K.f", "a.b.c.f", "a.b.f"]
    assert candidates("a.b", "", "x.y") == ["x.y", "a.b.x.y", "builtins.x.y"]
    assert candidates("a.b", "", "P.f", {"P": "a.c.P"})[2] == "a.c.P.f"
    assert _import("rockfall_design.errors")
    assert not _import("rockfall_design.no_such_name")


#: An issue or item number in prose ("issue 22", "issue #27", "(#27)", "item 8");
#: a colour ("#566573") or a numbered label ("#2 talus.restitution") is not one.
ISSUE_NUMBER = re.compile(r"\bissues? #?\d+\b|\(#\d+\)|\bitem \d+\b", re.I)


def test_no_issue_numbers_in_the_package() -> None:
    """Docstrings and comments say what they mean, not which issue asked for it."""
    found = []
    for folder, _ in SOURCES:
        for path in sorted(folder.rglob("*.py")):
            for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if ISSUE_NUMBER.search(line):
                    found.append(f"{path.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not found, "issue numbers in the package:\n" + "\n".join(found)
