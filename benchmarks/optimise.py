"""The optimiser on every bundled design project: speed, and how its answer holds up.

    python benchmarks/optimise.py [--projects projects/design_quarry.yaml ...] [--no-reference]
    python benchmarks/optimise.py --seeds 11,12,13,14,15 [--projects ...]
        [--max-rocks 100000,200000,400000] [--against /tmp/main] [--no-reference]
    python benchmarks/optimise.py --no-reference --check-seeds 977,978,...,996

For each project it prints

* the optimiser's wall time (warm: numba compiled first), designs screened,
  exact evaluations, rocks simulated and the chosen design's cost;
* the chosen design checked as an engineer would: ``rockfall-design check
  design.yaml --seed 977`` and ``--seed 978`` (or the ``--check-seeds``)
  with twice the rocks that decided it (the verdict on the point values,
  and with confidence, and each factor with its bound); with more than two
  check seeds, at how many the check confirms the design with confidence (a
  design chosen at its limit is confirmed by a checker's own seed only as
  often as the check's power at that many rocks allows);
* with ``--seeds``: each project at each seed (and each ``--max-rocks``
  budget), its choice, wall time, rocks simulated per deciding rock, the
  designs left marginal or undecided with the rocks that would decide them,
  the spread of the chosen cost and whether the dearer runs name the
  cheapest as marginal, every seed's choice checked at the check seeds with
  twice its deciding rocks (in process, as ``check design.yaml`` evaluates
  it; ``--check-seeds ""`` skips them) and against the grid reference below;
  then all of it as one markdown table, and with ``--against TREE`` the warm
  optimise at the first seed of another source tree (``git archive main |
  tar -x -C TREE``), timed in a fresh interpreter with ``PYTHONPATH=TREE`` at
  its own settings, beside this tree's;
* a reference the optimiser must come within 1 % of: the cheapest single
  fence or wall on a 2 m grid of stations, with every catalogue product and
  height, that ``check`` admits with confidence (``holds_with_confidence``)
  with 4x the project's rocks. The grid is first screened on those rocks
  (for a lone net the screening is the exact judgement); the designs that
  pass are then checked exactly, cheapest first, until one holds.

Figures are from one run on this machine; run it again to compare, never
against a number from memory.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from rockfall_design.errors import ProjectError
from rockfall_design.judge.design_spec import resolve_design, with_residual_target
from rockfall_design.judge.evaluation import evaluate_design
from rockfall_design.judge.placing import build_concept
from rockfall_design.optimiser import Screening
from rockfall_design.optimiser.driver import optimise
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project
from rockfall_design.run.simulation import run_in_memory

ROOT = Path(__file__).resolve().parents[1]
PROJECTS = sorted((ROOT / "projects").glob("design_*.yaml"))
GRID_M = 2.0


def _check(design: Path, rocks: int, seed: int) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "rockfall_design", "check", str(design), "--rocks",
         str(rocks), "--seed", str(seed), "--json"],
        capture_output=True, text=True, check=False)
    return json.loads(out.stdout)


def _factors(chk: dict) -> str:
    """``; reach_factor 1.04 (bound 0.98)`` for each factor check of a check's --json."""
    out = []
    for m in chk.get("measures", []):
        for c in m.get("checks", []):
            if c.get("name", "").endswith("_factor") and c.get("value") is not None:
                bound = "-" if c.get("bound") is None else f"{c['bound']:.3f}"
                out.append(f"{c['name']} {c['value']:.3f} (bound {bound})")
    return "; " + ", ".join(out) if out else ""


def _rate_interval(k: int, n: int) -> tuple[float, float]:
    """Two-sided 95 % Clopper-Pearson interval of a rate of k in n."""
    from scipy.stats import beta

    lo = 0.0 if k == 0 else float(beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(0.975, k + 1, n - k))
    return lo, hi


def reference(project, registry, rocks: int) -> tuple[float, str, int]:
    """Cheapest single fence or wall on the 2 m grid that holds with confidence at ``rocks``."""
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    proj, _ = with_residual_target(project, spec, project.rocks.count)
    screen = Screening(proj, registry, spec, concept, rocks=rocks, seed=project.rocks.seed)
    passing = []
    screened = 0
    for ci, cand in enumerate(spec.candidates):
        if not cand.products or ci in screen.edit_candidates:
            continue
        lo, hi = cand.x_range
        for x in lo + GRID_M * np.arange(math.floor((hi - lo) / GRID_M + 1e-9) + 1):
            for prod in cand.products:
                for h in prod.heights:
                    (m,) = screen.measures([(ci, {"x": float(x), "product": prod.name,
                                                  "height": h})])
                    r = screen.screen([m])
                    screened += 1
                    ok = r.feasible and all(c.holds_with_confidence for cs in r.checks
                                            for c in cs)
                    if ok:
                        passing.append((r.cost, m))
    exact = 0
    for cost, m in sorted(passing, key=lambda p: p[0]):
        ev = evaluate_design(proj, registry, [m], concept, rocks=rocks, seed=project.rocks.seed)
        exact += 1
        if ev.holds_with_confidence:
            return cost, f"{m.label()}", screened
    return math.inf, "none", screened


def _check_in_process(project, registry, best, seeds: list[int]) -> list[bool]:
    """The chosen design checked as ``check design.yaml --rocks 2n --seed s`` does, in process.

    design.yaml is the project with the chosen measures and the design's residual
    target as the protected zone's allowance; ``check`` evaluates it exactly at
    the project's confidence: the same evaluation here, without a process per check.
    """
    spec = resolve_design(project, registry)
    proj, _ = with_residual_target(project, spec, project.rocks.count)
    concept = build_concept(proj, registry)
    return [bool(evaluate_design(proj, registry, best.measures, concept,
                                 rocks=2 * best.decision_rocks, seed=s).holds_with_confidence)
            for s in seeds]


def _with_budget(project, max_rocks: int | None):
    """The project with ``design.max_rocks`` set (None: the project's own, or the default)."""
    if max_rocks is None:
        return project
    return project.model_copy(update={"design": project.design.model_copy(
        update={"max_rocks": int(max_rocks)})})


def _budget_of(project) -> int:
    return int(project.design.max_rocks)


def _run_line(seed: int, res, wall: float, cpu: float) -> tuple[str, dict]:
    """One run's line, and its row of the final table (``cpu``: the process's CPU time
    over the run, every thread's, which a machine shared with other work inflates less
    than the wall time)."""
    b = res.best
    cost = b.cost if b is not None else math.inf
    short = sum(1 for m in res.marginal if m.short_of_margin)
    marginal = sum(1 for m in res.marginal if m.decided) - short
    undecided = len(res.marginal) - marginal - short
    per = res.rocks_simulated / b.decision_rocks if b is not None else float("nan")
    line = (f"  seed {seed}: {cost:>12,.0f} {b.name if b else 'none':30s} {wall:5.1f} s "
            f"({cpu:.1f} s CPU), "
            f"{res.evaluations:,} screened, {res.exact_evaluations} exact, {marginal} "
            f"marginal, {short} short of the margin, {undecided} undecided listed, "
            f"{res.rocks_simulated:,} rocks simulated = {per:.1f} per deciding rock "
            f"({b.decision_rocks if b else 0:,})")
    row = {"seed": seed, "cost": cost, "wall": wall, "cpu": cpu,
           "deciding": b.decision_rocks if b else 0,
           "simulated": res.rocks_simulated, "per": per, "marginal": marginal,
           "short": short, "undecided": undecided}
    return line, row


def _listed_lines(res) -> list[str]:
    out = []
    if res.bare_slope and res.bare_slope["holds"]:
        out.append(f"      the bare slope already meets the residual target "
                   f"({res.bare_slope['reaching']} of {res.bare_slope['rocks']:,} reach)")
    for m in res.marginal[:8]:
        kind = ("short of the margin" if m.short_of_margin else
                "marginal" if m.decided else "not decided")
        out.append(f"      {kind}, cheaper: {m.cost:,.0f} {'; '.join(m.labels)} "
                   f"(about {m.rocks_to_decide or '?'} rocks would decide it)")
    if len(res.marginal) > 8:
        out.append(f"      ... {len(res.marginal) - 8} more listed")
    return out


def _spread_lines(seeds: list[int], rows: list[dict], named: list[dict]) -> list[str]:
    costs = [r["cost"] for r in rows]
    finite = [c for c in costs if math.isfinite(c)]
    if not finite:
        return ["  no seed chose a design"]
    low = min(finite)
    out = [f"  spread max/min {max(finite) / low:.3f} over {len(finite)} seeds"]
    # The criterion: within 3 %, or every dearer run's report names
    # the cheapest choice of the seeds as marginal or not decided.
    for seed, c, nm in zip(seeds, costs, named, strict=True):
        if math.isfinite(c) and c > 1.03 * low:
            m = nm.get(round(low, 2))
            out.append(f"  seed {seed}: {c:,.0f} is dearer than {low:,.0f} by more than "
                       f"3 %; its report names {low:,.0f}: "
                       + ("NO" if m is None else f"yes: {m.reason[:300]}"))
    return out


def _project_seeds(path: Path, project, registry, args, budget: int | None) -> list[dict]:
    """Every seed of one project at one budget; its lines printed, its table rows returned."""
    project = _with_budget(project, budget)
    print(f"\n{path.name} (design.max_rocks {_budget_of(project):,})", flush=True)
    rows, named = [], []
    checked = confirmed = 0
    for seed in args.seeds:
        t0, c0 = time.perf_counter(), time.process_time()
        res = optimise(project, registry, seed=seed)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        line, row = _run_line(seed, res, wall, cpu)
        print(line, flush=True)
        rows.append(row)
        named.append({round(m.cost, 2): m for m in res.marginal})
        b = res.best
        if b is not None and args.check_seeds:
            held = _check_in_process(project, registry, b, args.check_seeds)
            checked += len(held)
            confirmed += sum(held)
            print(f"      checked with {2 * b.decision_rocks:,} rocks at seeds "
                  + ", ".join(f"{cs}: {'holds' if h else 'NOT with confidence'}"
                              for cs, h in zip(args.check_seeds, held, strict=True)))
        for text in _listed_lines(res):
            print(text)
    if checked:
        lo, hi = _rate_interval(confirmed, checked)
        print(f"  every seed's choice checked at seeds {args.check_seeds}: holds with "
              f"confidence in {confirmed} of {checked} checks ({100 * lo:.0f} to "
              f"{100 * hi:.0f} % at 95 %)")
    print("\n".join(_spread_lines(args.seeds, rows, named)), flush=True)
    budget_used = _budget_of(project)
    return [{**r, "project": path.name, "budget": budget_used} for r in rows]


def _warm_times(tree: Path, projects: list[Path], seed: int) -> dict[str, dict]:
    """Warm optimise at ``seed`` of every project with the package of another ``tree``.

    Runs this script in a fresh interpreter with ``PYTHONPATH=tree`` (so that
    ``rockfall_design`` is that tree's), which loads the engine first and then
    times one optimise per project at the project's own settings.
    """
    import os

    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "--warm-json", "--seeds", str(seed),
         "--projects", *map(str, projects)], capture_output=True, text=True, env=env,
        check=False)
    if out.returncode != 0:
        print(f"  {tree}: failed (exit {out.returncode}): {out.stderr.strip()[-300:]}")
        return {}
    return json.loads(out.stdout.strip().splitlines()[-1])


def _warm_json(args: argparse.Namespace) -> None:
    """``--warm-json``: warm optimise times of this interpreter's package, as one JSON line."""
    import rockfall_design

    registry = load_registry()
    run_in_memory(load_project(args.projects[0]), rocks=10)
    out = {"package": str(Path(rockfall_design.__file__).parent)}
    for path in args.projects:
        project = load_project(path)
        try:
            resolve_design(project, registry)
        except ProjectError:
            continue
        t0, c0 = time.perf_counter(), time.process_time()
        res = optimise(project, registry, seed=args.seeds[0])
        b = res.best
        out[path.name] = {"wall": time.perf_counter() - t0, "cpu": time.process_time() - c0,
                          "cost": None if b is None else b.cost,
                          "budget": _budget_of(project),
                          "simulated": res.rocks_simulated}
    print(json.dumps(out))


def _table(rows: list[dict], other: dict[str, dict], tree: Path | None) -> None:
    """Every run as a markdown table (for docs/speed.md), and the warm comparison."""
    print("\n| project | max_rocks | seed | cost | deciding rocks | rocks simulated "
          "(per deciding rock) | wall s (CPU s) | marginal / short / undecided |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        cost = "none" if not math.isfinite(r["cost"]) else f"{r['cost']:,.0f}"
        print(f"| {r['project'].removesuffix('.yaml')} | {r['budget']:,} | {r['seed']} | "
              f"{cost} | {r['deciding']:,} | {r['simulated']:,} ({r['per']:.1f}) | "
              f"{r['wall']:.1f} ({r['cpu']:.1f}) | {r['marginal']} / {r['short']} / "
              f"{r['undecided']} |")
    if tree is None:
        return
    print(f"\nwarm optimise at its own settings, this tree against {tree} (same run):")
    first = {}
    for r in rows:
        first.setdefault((r["project"], r["budget"]), r)
    for (name, budget), r in first.items():
        o = other.get(name)
        if o is None or r["seed"] != other.get("_seed"):
            continue
        oc = "none" if o["cost"] is None else f"{o['cost']:,.0f}"
        print(f"  {name}: {r['wall']:.1f} s, {r['cpu']:.1f} s CPU (max_rocks {budget:,}, "
              f"cost {r['cost']:,.0f}) against {o['wall']:.1f} s, {o['cpu']:.1f} s CPU "
              f"(max_rocks {o['budget']:,}, cost {oc})")


def _seeds(args: argparse.Namespace) -> None:
    """Each project at each seed and budget: the choice, the spread, the listed designs."""
    registry = load_registry()
    run_in_memory(load_project(args.projects[0]), rocks=10)  # compile or load the engine first
    projects = []
    for path in args.projects:
        project = load_project(path)
        try:
            resolve_design(project, registry)
        except ProjectError as exc:
            print(f"\n{path.name}: skipped: {exc}")
            continue
        projects.append((path, project))
    other: dict[str, dict] = {}
    if args.against is not None:
        other = _warm_times(args.against, [p for p, _ in projects], args.seeds[0])
        other["_seed"] = args.seeds[0]
    rows = []
    for path, project in projects:
        for budget in args.max_rocks or [None]:
            rows += _project_seeds(path, project, registry, args, budget)
        if not args.no_reference:
            _reference_line(project, registry,
                            [r for r in rows if r["project"] == path.name])
    _table(rows, other, args.against)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak resident memory of this process: {rss:.0f} MiB")


def _reference_line(project, registry, rows: list[dict]) -> None:
    """The 2 m grid reference, and every run's choice against it (within 1 %?)."""
    t0 = time.perf_counter()
    ref, label, screened = reference(project, registry, 4 * project.rocks.count)
    print(f"  reference (2 m grid, single fence or wall, 4x rocks, with confidence): "
          f"{ref:,.0f} ({label}; {screened:,} designs, {time.perf_counter() - t0:.0f} s)")
    if not math.isfinite(ref):
        return
    for r in rows:
        ratio = r["cost"] / ref
        print(f"    max_rocks {r['budget']:,} seed {r['seed']}: chosen / reference = "
              f"{ratio:.3f}{'' if ratio <= 1.01 else '  (dearer by more than 1 %)'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--projects", type=Path, nargs="*", default=PROJECTS)
    ap.add_argument("--no-reference", action="store_true",
                    help="skip the 2 m grid reference (the slow part)")
    ap.add_argument("--seeds", type=lambda t: [int(x) for x in t.split(",")], default=None,
                    help="comma-separated seeds: run each project at each seed and print "
                    "each seed's choice, the spread of the chosen cost (max/min) and the "
                    "marginal designs cheaper than a dearer choice (e.g. 11,12,13,14,15)")
    ap.add_argument("--check-seeds", type=lambda t: [int(x) for x in t.split(",") if x],
                    default=[977, 978],
                    help="comma-separated seeds at which the chosen design (at the project's "
                    "own seed) is checked with twice its deciding rocks; with more than two, "
                    "how many confirm it with confidence (e.g. 977,978,...,996)")
    ap.add_argument("--max-rocks", type=lambda t: [int(x) for x in t.split(",")],
                    default=None,
                    help="with --seeds: comma-separated rock budgets (design.max_rocks) to run "
                    "every project at (default: each project's own, or the default budget)")
    ap.add_argument("--against", type=Path, default=None,
                    help="with --seeds: another source tree (e.g. an export of main); its "
                    "warm optimise at the first seed is timed in a fresh interpreter with "
                    "PYTHONPATH=TREE, at its own settings, and printed beside this tree's")
    ap.add_argument("--warm-json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.warm_json:
        return _warm_json(args)
    if args.seeds:
        return _seeds(args)
    registry = load_registry()
    t0 = time.perf_counter()
    run_in_memory(load_project(args.projects[0]), rocks=10)
    print(f"first call (compile or load numba's cache): {time.perf_counter() - t0:.1f} s")
    for path in args.projects:
        project = load_project(path)
        try:
            resolve_design(project, registry)
        except ProjectError as exc:  # e.g. design_embankment.yaml without its example plugin
            print(f"\n{path.name}: skipped: {exc}")
            continue
        t0 = time.perf_counter()
        res = optimise(project, registry)
        wall = time.perf_counter() - t0
        best = res.best
        print(f"\n{path.name}: {wall:.1f} s wall, {res.evaluations:,} designs screened, "
              f"{res.exact_evaluations} exact evaluations, {res.rocks_simulated:,} rocks "
              f"simulated, {res.edit_runs} ground-edit runs")
        for a in res.alternatives:
            cost = "-" if not math.isfinite(a.cost) else f"{a.cost:,.0f}"
            print(f"  {a.name:34s} {cost:>10s}  holds={a.holds}  "
                  f"{(a.reason or a.proof)[:110]}")
        if best is None:
            print("  chosen: none")
            continue
        print(f"  chosen: {best.name} {best.cost:,.0f} {res.currency}, decided with "
              f"{best.decision_rocks:,} rocks, fresh {best.fresh_rocks:,} rocks: "
              f"{'holds' if best.holds_on_fresh_rocks else 'FAILS'}")
        with tempfile.TemporaryDirectory() as tmp:
            code = subprocess.run(
                [sys.executable, "-m", "rockfall_design", "optimise", str(path), "--out",
                 tmp, "--json"], capture_output=True, text=True, check=False).returncode
            design = Path(tmp) / "design.yaml"
            if code != 0 or not design.exists():
                print(f"  optimise --out gave no design.yaml (exit {code})")
                continue
            confirmed = 0
            for seed in args.check_seeds:
                chk = _check(design, 2 * best.decision_rocks, seed)
                confirmed += bool(chk["holds_with_confidence"])
                print(f"  check design.yaml --seed {seed} --rocks {2 * best.decision_rocks:,}: "
                      f"ok={chk['ok']} holds_with_confidence={chk['holds_with_confidence']} "
                      f"residual {chk['protect']['reaching']} "
                      f"(upper {100 * chk['protect']['upper_fraction']:.3f} %)"
                      + _factors(chk))
            if len(args.check_seeds) > 2:
                # How often a checker who reruns the check at a seed of their own
                # confirms the design with confidence (its power at that many
                # rocks), with the Clopper-Pearson interval of that rate.
                lo, hi = _rate_interval(confirmed, len(args.check_seeds))
                print(f"  confirmed with confidence at {confirmed} of {len(args.check_seeds)} "
                      f"checker seeds ({100 * lo:.0f} to {100 * hi:.0f} % at 95 %)")
        if args.no_reference:
            continue
        t0 = time.perf_counter()
        ref, label, screened = reference(project, registry, 4 * project.rocks.count)
        ratio = best.cost / ref if math.isfinite(ref) else float("nan")
        print(f"  reference (2 m grid, single fence or wall, 4x rocks, with confidence): "
              f"{ref:,.0f} ({label}; {screened:,} designs, {time.perf_counter() - t0:.0f} s); "
              f"chosen / reference = {ratio:.3f}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak resident memory: {rss:.0f} MiB")


if __name__ == "__main__":
    main()
