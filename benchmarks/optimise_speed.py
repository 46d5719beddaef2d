"""Wall time, CPU time and peak memory of ``optimise``, this tree against another.

    python benchmarks/optimise_speed.py [--against TREE] [--seed 11] [--repeats 1]
        [--projects projects/design_two_zones.yaml projects/design_ditch_or_fence.yaml]

Each project is optimised as a user runs it, ``rockfall-design optimise
PROJECT --seed S --out DIR`` at the project's own budget, in a fresh
process per run, and the child's own wall time, CPU time (user and system:
what a machine shared with other work moves least) and resident peak are
printed. With ``--against TREE`` (another source tree, e.g. ``git archive
main | tar -x -C TREE``) the same runs of that tree's package and built-in
plugins (``PYTHONPATH=TREE:TREE/plugins``, and ``python -P``, so that
the folder a child runs in does not come first) alternate with this tree's in the
same session, and the files each writes (design.yaml, alternatives.csv,
barriers.csv) are compared byte for byte: a change of speed only must not
change them. Each tree's engine is loaded (compiled, if its sources are new
to this machine) by a small ``simulate`` first, so every timed run is warm.

Figures are from one run on this machine; run it again to compare, never
against a number from memory.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from engine import run_child_full

ROOT = Path(__file__).resolve().parents[1]
PROJECTS = [ROOT / "projects" / "design_two_zones.yaml",
            ROOT / "projects" / "design_ditch_or_fence.yaml"]
#: The files of ``optimise --out`` that depend on the results only (summary.json
#: also holds the run record: times, versions).
COMPARED = ("design.yaml", "alternatives.csv", "barriers.csv")


def _env(tree: Path | None) -> dict[str, str]:
    """The environment of a child that runs ``tree``'s package and plugins (this one if None)."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    if tree is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(tree), str(tree / "plugins")])
    return env


def _python() -> list[str]:
    """This interpreter running the package's command line.

    ``-P``: the child runs in this tree's folder, which ``-m`` would put first
    on ``sys.path``, ahead of ``PYTHONPATH``'s other tree.
    """
    return [sys.executable, "-P", "-m", "rockfall_design"]


def _warm(tree: Path | None, project: Path) -> None:
    """Load (or compile) ``tree``'s engine before anything is timed, after making sure
    that a child imports ``tree``'s package (this tree's where None)."""
    _, _, where, _, _ = run_child_full(
        [sys.executable, "-P", "-c", "import rockfall_design as p; print(p.__file__)"],
        _env(tree))
    if Path(where.strip()).resolve().parents[1] != (tree or ROOT).resolve():
        raise SystemExit(f"a child imports {where.strip()}, not the package of {tree or ROOT}")
    run_child_full([*_python(), "simulate", str(project), "--rocks", "10"], _env(tree))


def _optimise(tree: Path | None, project: Path, seed: int,
              out: Path) -> tuple[float, float, float, dict[str, bytes]]:
    """One optimise: wall (s), CPU (s), resident peak (MiB) and the compared files' bytes."""
    wall, rss, _, _, cpu = run_child_full(
        [*_python(), "optimise", str(project), "--seed", str(seed), "--out", str(out)],
        _env(tree))
    files = {name: (out / name).read_bytes() for name in COMPARED if (out / name).exists()}
    return wall, cpu, rss, files


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--against", type=Path, default=None, metavar="TREE",
                    help="another source tree to time in the same session")
    ap.add_argument("--projects", type=Path, nargs="+", default=PROJECTS)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--repeats", type=int, default=1)
    args = ap.parse_args()
    trees: dict[str, Path | None] = {"this tree": None}
    if args.against is not None:
        trees[f"{args.against}"] = args.against.resolve()
    for tree in trees.values():
        _warm(tree, args.projects[0])
    print(f"optimise --seed {args.seed}, warm engine, load {os.getloadavg()[0]:.1f}")
    print("| project | tree | wall s | CPU s | peak RSS MiB | outputs |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for project in args.projects:
            first: dict[str, bytes] | None = None
            for k in range(args.repeats):
                # Alternate the order, so that neither tree always runs on a busier machine.
                order = list(trees.items())[:: 1 if k % 2 == 0 else -1]
                for name, tree in order:
                    out = Path(tmp) / f"{project.stem}-{k}-{len(name)}"
                    wall, cpu, rss, files = _optimise(tree, project, args.seed, out)
                    first = files if first is None else first
                    same = "same" if files == first else "DIFFER: " + ", ".join(
                        n for n in COMPARED if files.get(n) != first.get(n))
                    print(f"| {project.stem} | {name} | {wall:.1f} | {cpu:.1f} | {rss:.0f} | "
                          f"{same} |", flush=True)


if __name__ == "__main__":
    main()
