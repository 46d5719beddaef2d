"""How the answer moves with engine.v_contact, with the hop criterion and without it.

    python benchmarks/transition.py [--rocks 1000] [--seed 5] [--projects a.yaml ...]

For issue 35's steep-to-flat section (soil rolling resistance 0.7, hard
ground 1.0) and every bundled project (projects/*.yaml that simulate runs),
the same rocks are run at v_contact = 2, 1, 0.5, 0.25, 0.1, 0.05 and
0.02 m/s, once without the hop criterion (engine.contact_hop_ratio 0: the
behaviour before it, where v_contact alone decides between flight and
contact) and once with it (the project's own ratio, 0.1 by default;
docs/PHYSICS.md, "The transition to contact"). Printed per setting: the
median stop (end) position with its two-sided 95 % distribution-free
interval (order statistics, rockfall_design.judge.bounds) and the share of
rocks past the last analysis station (or protect.x where there is none) with
its Clopper-Pearson interval; and, per project and mode, whether every
setting from 0.25 m/s down agrees with the smallest within those intervals.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import rockfall_design as rd  # noqa: E402
from rockfall_design.errors import RockfallError  # noqa: E402
from rockfall_design.judge.bounds import (  # noqa: E402
    fraction_lower_bound,
    fraction_upper_bound,
    quantile_with_bounds,
)

SETTINGS = (2.0, 1.0, 0.5, 0.25, 0.1, 0.05, 0.02)
"""v_contact (m/s), from the old default's fourfold down to a fortieth of it."""

CONVERGED_FROM = 0.25
"""Settings at or below this (m/s) must agree with the smallest."""

STEEP_TO_FLAT = {
    "name": "Steep to flat",
    "description": "A 35 degree soil slope onto flat hard ground (issue 35).",
    "slope": {"points": [[0, 60], [10, 58], [70, 16], [75, 15], [250, 15]],
              "materials": ["soil", "soil", "soil", "hard"]},
    "materials": {
        "soil": {"restitution": 0.3, "friction": 0.6, "rolling_resistance": 0.7,
                 "roughness_deg": 4},
        "hard": {"restitution": 0.5, "friction": 0.5, "rolling_resistance": 1.0,
                 "roughness_deg": 8},
    },
    "rocks": {"count": 2000, "seed": 3, "volume": {"lognormal": [0.3, 0.6]},
              "release": {"x": [2, 8], "height": 16, "velocity": [0.5, 0]}},
    "analysis": {"stations": [40, 72, 100]},
    "protect": {"x": 200},
}
"""Issue 35's steep-to-flat case: soil rolling resistance 0.7, hard ground 1.0."""


def _variant(data: dict, v_contact: float, hop: bool) -> str:
    """The project text with ``engine.v_contact`` set and the criterion on or off."""
    out = dict(data)
    engine = dict(out.get("engine") or {}, v_contact=v_contact)
    if not hop:
        engine["contact_hop_ratio"] = 0.0
    out["engine"] = engine
    return yaml.safe_dump(out, sort_keys=False)


def figures(data: dict, base: Path, v_contact: float, hop: bool, rocks: int, seed: int
            ) -> dict[str, tuple[float, float | None, float | None]]:
    """Median end x (m) and share past the last station, each (value, lower, upper)."""
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", dir=base, delete=False) as f:
        f.write(_variant(data, v_contact, hop))
    try:
        res = rd.simulate(f.name, rocks=rocks, seed=seed, trajectories=0)
    finally:
        Path(f.name).unlink()
    end_x = res.rocks["end_x_m"].to_numpy()
    stations = list((data.get("analysis") or {}).get("stations") or [])
    last = max(stations) if stations else float((data.get("protect") or {}).get("x", np.nan))
    out = {"median end x (m)": quantile_with_bounds(end_x, 0.5, 0.975)}
    if np.isfinite(last):
        n = end_x.size
        k = int((res.rocks["max_x_m"].to_numpy() > last).sum())
        out[f"share past {last:g} m"] = (k / n, fraction_lower_bound(k, n, 0.975),
                                         fraction_upper_bound(k, n, 0.975))
    return out


def _overlap(a: tuple, b: tuple) -> bool:
    """Whether two (value, lower, upper) intervals overlap (an open end overlaps)."""
    lo_a, hi_a = (-np.inf if a[1] is None else a[1]), (np.inf if a[2] is None else a[2])
    lo_b, hi_b = (-np.inf if b[1] is None else b[1]), (np.inf if b[2] is None else b[2])
    return lo_a <= hi_b and lo_b <= hi_a


def _fmt(t: tuple) -> str:
    v, lo, hi = (np.nan if x is None else x for x in t)
    return f"{v:8.3f} [{lo:8.3f}, {hi:8.3f}]" if abs(v) < 10 else f"{v:8.1f} [{lo:8.1f}, {hi:8.1f}]"


def report(name: str, data: dict, base: Path, rocks: int, seed: int) -> bool:
    """Print one project's table; True if, with the criterion, it has converged."""
    print(f"\n{name} ({rocks} rocks, seed {seed})")
    ok_after = True
    for hop in (False, True):
        rows = {vc: figures(data, base, vc, hop, rocks, seed) for vc in SETTINGS}
        ref = rows[SETTINGS[-1]]
        agree = all(_overlap(rows[vc][k], ref[k]) for vc in SETTINGS if vc <= CONVERGED_FROM
                    for k in ref)
        ok_after &= agree or not hop
        print(f"  {'after (hop criterion)' if hop else 'before (v_contact alone)'}: "
              f"0.25 to 0.02 m/s agree: {agree}")
        for vc in SETTINGS:
            print(f"    v_contact {vc:5.2f}: " + "   ".join(
                f"{k} {_fmt(rows[vc][k])}" for k in ref))
    return ok_after


def _bundled() -> list[Path]:
    """Bundled project files (the catalogues and the materials library are not projects)."""
    skip = {"materials.yaml", "catalogue_costs.yaml", "catalogue_products.yaml"}
    return [p for p in sorted((ROOT / "projects").glob("*.yaml")) if p.name not in skip]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--projects", nargs="*", default=None)
    args = ap.parse_args(argv)
    ok = report("steep to flat", STEEP_TO_FLAT, ROOT / "projects",
                args.rocks, args.seed)
    paths = [Path(p).resolve() for p in args.projects] if args.projects else _bundled()
    for path in paths:
        try:
            ok &= report(path.name, yaml.safe_load(path.read_text()), path.parent,
                         args.rocks, args.seed)
        except RockfallError as exc:
            print(f"\n{path.name}: not run by simulate ({str(exc).splitlines()[0]})")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
