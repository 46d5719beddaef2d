"""The house in numbers: how the package's files import each other, and their sizes.

    python benchmarks/house.py [PACKAGE_DIR] [--list]

Counts, from the code alone (its syntax trees; nothing is imported), over
the package and the built-in plugins' package (``plugins/``, or the folders
given with ``--beside``), the figures the house's targets are set on:

* import cycles between files (strongly connected components of the graph of
  every import, at module level or inside a function, ``if TYPE_CHECKING:``
  imports left out), as ``/work/shared/tools/import_cycles.py`` counts them;
* imports running back up the rooms' order (below);
* loose files: ``*.py`` files at the top of the package, ``__init__.py`` and
  ``__main__.py`` included;
* modules over 600 lines and functions over 120 lines, outside the compiled
  kernel (functions decorated with numba's ``njit``/``jit`` or the engine's
  ``hot``; a module is part of the kernel when most of its function lines are);
* and imports of another file's ``_private``
  names, and file names that occur more than once (in the package and the
  built-in plugins' package);
* the largest module of the built-in plugins (the built-ins are meant to be
  one small module per measure, safety concept or cost model).

The rooms' order (docs of the architecture, DESIGN.md)::

    cli -> api -> optimiser / studies / calibration -> judge -> run -> engine

with project, plugins, report and arguments (the bounds of a run's numbers,
shared by the project file, the API and the commands) beside them. An
import counts as running
back up when it goes from a room to one earlier in that chain; when a room
beside the chain (project, plugins, report, errors) imports the commands or
the API; when the engine imports anything outside itself (it is numpy and
numba only); or when errors.py imports anything of the package. A file's
room is its package (``optimiser/`` is the optimiser, ``studies/`` the
studies); the files still loose at the top of the package are given the room
they belong to in :data:`LOOSE` (unknown ones are reported as such). The
built-ins are a room of their own, a client of the public API: an import of
them from the package runs back up (the package finds them through their
entry points only).

Prints the figures; ``--list`` adds every offending item. Exit code 0
always: it measures, it does not judge (a test may judge later).
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Position in the chain of rooms; a lower number is further up.
CHAIN = {"cli": 0, "testing": 0, "api": 1, "trial": 2, "optimiser": 2, "studies": 2,
         "calibration": 2, "judge": 3, "run": 4, "engine": 6}
#: Rooms beside the chain: imported from anywhere, importing neither cli nor api.
BESIDE = {"project", "plugins", "report", "errors", "limits"}

#: Sub-packages (first directory under the package) -> room.
PACKAGES = {"cli": "cli", "engine": "engine", "judge": "judge", "run": "run",
            "optimise": "optimiser", "optimiser": "optimiser", "study": "studies",
            "studies": "studies", "calibration": "calibration", "project": "project",
            "plugins": "plugins", "report": "report", "serve": "cli", "trial": "trial"}

#: Files inside a sub-package whose room is another one (what they do, not where they are).
MOVED: dict[str, str] = {}

#: Files loose at the top of the package -> the room they belong to (what each does).
LOOSE = {
    "__init__.py": "api", "__main__.py": "cli", "api.py": "api", "testing.py": "testing",
    "errors.py": "errors", "version.py": "errors", "limits.py": "limits",
    "results.py": "api",
}

MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 120
KERNEL_DECORATORS = {"njit", "jit", "hot", "vectorize", "guvectorize"}


@dataclass
class Package:
    """The package's files, parsed, and the import graph between them."""

    root: Path
    beside: list[Path] = field(default_factory=list)          # the built-ins' folders
    files: dict[str, Path] = field(default_factory=dict)     # dotted module -> file
    trees: dict[str, ast.Module] = field(default_factory=dict)
    edges: dict[str, set[str]] = field(default_factory=dict)  # module -> modules it imports
    private: list[tuple[str, str, str]] = field(default_factory=list)  # (importer, module, name)


def _modules(root: Path) -> dict[str, Path]:
    out = {}
    for p in sorted(root.rglob("*.py")):
        parts = list(p.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


def _type_checking_lines(tree: ast.Module) -> set[int]:
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            lines |= {sub.lineno for sub in ast.walk(node)
                      if isinstance(sub, ast.Import | ast.ImportFrom)}
    return lines


def load(root: Path, beside: list[Path] | None = None) -> Package:
    """Parse the package at ``root`` and the packages ``beside`` it; build the import graph."""
    beside = beside or []
    files = _modules(root)
    for folder in beside:
        files.update(_modules(folder))
    pkg = Package(root=root, beside=beside, files=files)

    def resolve(name: str) -> str | None:
        while name:
            if name in pkg.files:
                return name
            name = name.rpartition(".")[0]
        return None

    for mod, path in pkg.files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        pkg.trees[mod] = tree
        pkg.edges[mod] = set()
        here = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        skip = _type_checking_lines(tree)
        for node in ast.walk(tree):
            if not isinstance(node, ast.Import | ast.ImportFrom) or node.lineno in skip:
                continue
            if isinstance(node, ast.Import):
                targets = [[a.name] for a in node.names]
            else:
                base = node.module or ""
                if node.level:
                    anchor = here.split(".")[: len(here.split(".")) - (node.level - 1)]
                    base = ".".join(anchor + ([node.module] if node.module else []))
                # `from a import b`: b is a module of its own, or a name of a.
                targets = [[f"{base}.{a.name}", base] for a in node.names]
                target_mod = resolve(base)
                if target_mod and target_mod != mod:
                    pkg.private += [(mod, target_mod, a.name) for a in node.names
                                    if a.name.startswith("_") and not a.name.startswith("__")
                                    and f"{base}.{a.name}" not in pkg.files]
            for names in targets:
                for t in names:
                    r = resolve(t)
                    if r:
                        if r != mod:
                            pkg.edges[mod].add(r)
                        break
    return pkg


def room(pkg: Package, mod: str) -> str:
    """The room of a module (see the module's docstring)."""
    if not pkg.files[mod].is_relative_to(pkg.root):
        return "builtins"
    rel = pkg.files[mod].relative_to(pkg.root).as_posix()
    if rel in MOVED:
        return MOVED[rel]
    first, _, rest = rel.partition("/")
    if rest:
        return PACKAGES.get(first, f"?{first}")
    return LOOSE.get(first, f"?{first}")


def runs_up(src: str, dst: str) -> bool:
    """True if an import from room ``src`` into room ``dst`` runs back up the order."""
    if src == dst:
        return False
    if dst == "builtins":
        return True
    if src == "engine" or src == "errors":
        return True
    if src in CHAIN and dst in CHAIN:
        return CHAIN[dst] < CHAIN[src]
    if src in BESIDE and dst in CHAIN:
        return CHAIN[dst] <= CHAIN["api"]
    return False


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one file (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for start in edges:
        if start in index:
            continue
        work = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on.add(start)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return out


def _is_kernel(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    for dec in fn.decorator_list:
        node = dec.func if isinstance(dec, ast.Call) else dec
        name = node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")
        if name in KERNEL_DECORATORS:
            return True
    return False


def sizes(pkg: Package) -> tuple[list[tuple[str, int]], list[tuple[str, int]]]:
    """Modules over the line limit and functions over theirs, the compiled kernel left out."""
    modules, functions = [], []
    for mod, tree in pkg.trees.items():
        n_lines = len(pkg.files[mod].read_text(encoding="utf-8").splitlines())
        kernel_lines = plain_lines = 0
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if _is_kernel(node):
                    kernel_lines += length
                else:
                    plain_lines += length
                    if length > MAX_FUNCTION_LINES:
                        functions.append((f"{mod}.{node.name}", length))
        if n_lines > MAX_MODULE_LINES and kernel_lines <= plain_lines:
            modules.append((mod, n_lines))
    return sorted(modules, key=lambda m: -m[1]), sorted(functions, key=lambda f: -f[1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("package", nargs="?", type=Path, default=ROOT / "rockfall_design")
    ap.add_argument("--beside", type=Path, action="append",
                    default=[ROOT / "plugins" / "rockfall_design_builtins"],
                    help="other source folders read with the package (the built-ins)")
    ap.add_argument("--list", action="store_true", help="list every offending item")
    args = ap.parse_args(argv)
    beside = [d.resolve() for d in args.beside]
    pkg = load(args.package.resolve(), beside)

    circles = cycles(pkg.edges)
    rooms = {m: room(pkg, m) for m in pkg.files}
    up = sorted((a, b) for a in pkg.edges for b in pkg.edges[a]
                if runs_up(rooms[a], rooms[b]))
    unknown = sorted(m for m, r in rooms.items() if r.startswith("?"))
    loose = sorted(p.name for p in pkg.root.glob("*.py"))
    builtins = sorted(((m, len(p.read_text(encoding="utf-8").splitlines()))
                       for m, p in pkg.files.items() if rooms[m] == "builtins"),
                      key=lambda mn: -mn[1])
    modules, functions = sizes(pkg)
    paths = list(pkg.files.values())
    names = Counter(p.name for p in paths if p.name not in ("__init__.py", "__main__.py"))
    twice = sorted(n for n, c in names.items() if c > 1)
    n_edges = sum(len(e) for e in pkg.edges.values())

    rows = [
        ("files", len(pkg.files), f"{len(builtins)} of them built-ins"),
        ("import edges between files", n_edges, ""),
        ("import cycles", len(circles),
         f"{sum(len(c) for c in circles)} files in them; target 0"),
        ("imports running back up the rooms", len(up), "target at most 5"),
        ("loose files at the top of the package", len(loose), "target at most 8"),
        (f"modules over {MAX_MODULE_LINES} lines", len(modules), "outside the kernel; target 0"),
        (f"functions over {MAX_FUNCTION_LINES} lines", len(functions),
         "outside the kernel; target 0"),
        ("imports of another file's _private names", len(pkg.private), ""),
        ("file names that occur twice or more", len(twice), ""),
        ("lines of the largest built-in module", builtins[0][1] if builtins else 0,
         builtins[0][0] if builtins else "no built-ins read"),
    ]
    width = max(len(r[0]) for r in rows)
    for label, value, note in rows:
        print(f"{label:<{width}}  {value:>5}  {note}")
    if unknown:
        print(f"files of no known room: {', '.join(unknown)}")
    if args.list:
        for c in circles:
            print("cycle:", ", ".join(c))
        for a, b in up:
            print(f"up: {a} ({rooms[a]}) -> {b} ({rooms[b]})")
        print("loose:", ", ".join(loose))
        for m, n in modules:
            print(f"module: {m} {n} lines")
        for f, n in functions:
            print(f"function: {f} {n} lines")
        for a, b, name in sorted(pkg.private):
            print(f"private: {a} takes {name} from {b}")
        print("twice:", ", ".join(twice))
    return 0


if __name__ == "__main__":
    sys.exit(main())
