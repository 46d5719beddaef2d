"""Golden record: hashes of every engine and command output, compared across refactors.

    python benchmarks/golden.py            # print the hashes, compare with golden.json
    python benchmarks/golden.py --write    # store them as the reference

A restructuring must leave every result bit-identical. This runs a few bundled
projects with a few hundred rocks at two seeds (simulate, check, optimise, and the engine
itself with barriers, restart stations, trajectories, recorded speed and a
resumed run) and hashes every output array, DataFrame and JSON summary. The
reference lives beside this script (benchmarks/golden.json); it is not a test
because a deliberate change of the physics changes it too.
"""

from __future__ import annotations

import argparse
import atexit
import hashlib
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = Path(__file__).with_name("golden.json")
SEEDS = (3, 11)
ROCKS = 300


VOLATILE = {"runtime_s"}
"""Keys of the JSON summaries that measure the machine, not the result."""


def _stable(obj: Any) -> Any:
    """``obj`` without its volatile keys (wall times)."""
    if isinstance(obj, dict):
        return {k: _stable(v) for k, v in obj.items() if k not in VOLATILE}
    if isinstance(obj, list):
        return [_stable(v) for v in obj]
    return obj


def _digest(obj: Any) -> str:
    """A short hash of an array, a DataFrame, a list of arrays or a JSON-able object."""
    import pandas as pd

    h = hashlib.sha256()
    if isinstance(obj, pd.DataFrame):
        h.update(json.dumps([str(c) for c in obj.columns]).encode())
        h.update(pd.util.hash_pandas_object(obj, index=True).to_numpy().tobytes())
    elif isinstance(obj, np.ndarray):
        h.update(str(obj.dtype).encode() + str(obj.shape).encode())
        h.update(np.ascontiguousarray(obj).tobytes())
    elif isinstance(obj, list) and all(isinstance(a, np.ndarray) for a in obj):
        for a in obj:
            h.update(_digest(a).encode())
    else:
        h.update(json.dumps(_stable(obj), sort_keys=True, default=str).encode())
    return h.hexdigest()[:16]


def _engine(seed: int) -> dict[str, str]:
    """Every array of run_ensemble on the benchmark slope, with barriers, and a resumed run."""
    from rockfall_design.engine import barrier_table, run_ensemble
    from rockfall_design.engine.problem import EnsembleResult
    from rockfall_design.project import load_project
    from rockfall_design.run.releases import (
        draw_releases,
        engine_key,
        engine_settings,
        section_from_project,
    )

    project = load_project(ROOT / "projects" / "quarry_road.yaml")
    section = section_from_project(project)
    rel = draw_releases(project, ROCKS, seed)
    bars = np.vstack([
        barrier_table(60.0, 3.0, 2.0e6, 0),                         # net
        barrier_table(95.0, 1.5, 5.0e5, 1, restitution=0.3),        # rigid
        barrier_table(112.0, 1.0, 1.0e6, 2, gap_m=1.0, spacing_m=2.5),  # blocks
    ])
    common = dict(
        key=engine_key(seed), stations=[50.0, 90.0, 115.0], grid=np.arange(0.0, 160.0, 2.5),
        settings=engine_settings(project), threads=1, batch_size=97,
    )
    out: dict[str, str] = {}
    r1 = run_ensemble(section, rel, barriers=bars, restart_stations=[40.0, 80.0],
                      record_speed=True, n_trajectories=5, **common)
    r2 = run_ensemble(section, rel, restart_stations=[80.0], **common)
    mask = ~np.isnan(r2.restart_state[:, 0, 0])
    r3 = run_ensemble(section, rel, barriers=bars[:1],
                      resume=(mask, r2.restart_state[:, 0], r2.restart_rng[:, 0]), **common)
    for tag, res in (("barriers", r1), ("restart", r2), ("resumed", r3)):
        for name in EnsembleResult.__dataclass_fields__:
            out[f"engine.{tag}.{name}"] = _digest(getattr(res, name))
    return out


def _commands(seed: int) -> dict[str, str]:
    """simulate, check and optimise of bundled projects through the public API."""
    import rockfall_design as rd

    out: dict[str, str] = {}
    for name in ("benchmark", "quarry_road", "standard_slope"):
        r = rd.simulate(ROOT / "projects" / f"{name}.yaml", rocks=ROCKS, seed=seed,
                        trajectories=3)
        out[f"simulate.{name}.summary"] = _digest(r.summary)
        out[f"simulate.{name}.rocks"] = _digest(r.rocks)
        out[f"simulate.{name}.crossings"] = _digest(r.crossings)
    for name in ("quarry_fence_ditch", "benchmark", "quarry_fence_too_small"):
        c = rd.check(ROOT / "projects" / f"{name}.yaml", rocks=ROCKS, seed=seed, trajectories=3)
        out[f"check.{name}.summary"] = _digest(c.summary)
        out[f"check.{name}.rocks"] = _digest(c.rocks)
        out[f"check.{name}.measures"] = _digest(c.measures)
    o = rd.optimise(ROOT / "projects" / "design_ditch_or_fence.yaml", rocks=ROCKS, seed=seed)
    out["optimise.design_ditch_or_fence.summary"] = _digest(o.summary)
    out["optimise.design_ditch_or_fence.alternatives"] = _digest(o.alternatives)
    return out


def record() -> dict[str, str]:
    """Every hash, keyed by seed and output."""
    out: dict[str, str] = {}
    for seed in SEEDS:
        for k, v in {**_engine(seed), **_commands(seed)}.items():
            out[f"seed{seed}.{k}"] = v
    return out


def main(argv: list[str] | None = None) -> int:
    # numba's cache knows a function by its own file only: a kernel cached
    # before a callee in another module changed would run the old callee. A
    # fresh cache makes every comparison compile what the sources say (~30 s).
    cache = tempfile.mkdtemp(prefix="rockfall-golden-")
    atexit.register(shutil.rmtree, cache, True)
    os.environ["NUMBA_CACHE_DIR"] = cache
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="store the hashes as the reference")
    args = ap.parse_args(argv)
    now = record()
    if args.write:
        REFERENCE.write_text(json.dumps(now, indent=1, sort_keys=True) + "\n")
        print(f"{len(now)} hashes written to {REFERENCE}")
        return 0
    ref = json.loads(REFERENCE.read_text())
    bad = sorted(k for k in set(ref) | set(now) if ref.get(k) != now.get(k))
    for k in bad:
        print(f"DIFFERS {k}: {ref.get(k)} -> {now.get(k)}")
    print(f"{len(now)} hashes, {len(bad)} differ from {REFERENCE.name}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
