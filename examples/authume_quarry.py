"""The Authume quarry rockfall tests as two calibration projects (P1 and P2).

Full-scale tests in the Authume quarry (France, national project C2ROP):
blocks of about 0.1 to 0.75 m3 were dropped from two points above a
vegetated slope and came to rest on benches and the quarry floor below; the
stop positions and masses of 41 blocks on profile P1 and 48 on profile P2,
the terrain (a photogrammetric surface in three zones: vegetated slopes, hard
surfaces, rocky slopes) and the drop points were published by Garcia,
Villard, Richefeu and Daudon with their paper on the tests (see
docs/calibration.md, "A real site"). The data are not bundled here (the
repository that holds them states no licence); this script reads the user's
own copy::

    git clone https://github.com/richefeu/AuthumeQuarryRockfalls_Data-in-Brief authume-data
    python examples/authume_quarry.py authume-data authume

and writes into the output folder, for each profile:

- ``section_P1.csv``: the 2-D section along the profile, cut from the
  terrain surface (``Geometries/STL/DTM_*_zone.stl``) on the line from the
  drop point to the middle of the blocks' stops on the map: the height of
  the surface every ``--step`` m, simplified (points whose removal moves the
  line by less than ``--tolerance`` m are dropped); each segment's material
  from the zone beneath it and its steepness: ``wall`` (steeper than
  ``--wall-deg``, any zone), ``vegetated`` (blue zone), ``floor`` (grey
  zone: benches and the quarry floor), ``rocky`` (red zone);
- ``stops_P1.csv``: each block's station on that line (``x``, m) and its
  mass (``mass_kg``), with its distance from the line on the map
  (``offset_m``, for the reader: ``calibrate`` ignores it);
- ``authume_P1.yaml``: a project on that section, with the materials of
  ``starting_materials.yaml`` (textbook values, the issue's: soil 0.3, 0.6,
  0.4; rock 0.5, 0.5, 0.15), the rocks dropped from the published drop
  points, and a ``calibrate:`` section (its levels the benches and the floor
  of the profile);
- ``stops_P1_a.csv`` and ``stops_P1_b.csv``: profile P1's blocks split at
  random into two halves (by block, ``--split-seed``), to calibrate on one
  (``calibrate authume_P1.yaml --observed stops_P1_a.csv``) and predict the
  other (``compare``);
- ``authume_P2_calibrated.yaml`` (and ``authume_P1_calibrated.yaml``): the
  profile's project on the materials that ``calibrate --save-materials
  calibrated_materials.yaml`` writes, to predict P2 with what was fitted on
  P1 (``compare``).

With ``--law rough_soft`` the projects take, in place of the textbook
values, the bundled library's ``ground_`` classes of the ``rough_soft`` law
by role (``ground_materials.yaml``: the vegetated slope
``ground_vegetated_slope``, the walls ``ground_rock_face``, the benches and
the floor ``ground_hard_floor``, rocky slopes ``ground_talus``), and their
``calibrate:`` says ``fit: auto`` (the rolling resistance of every material
on the section over its class's range, docs/calibration.md). Sections and
stops are the same for either law.

With ``--trace fall-line`` the section follows the terrain's fall line from
the drop point down to the first flat ground, then runs straight to the
middle of the stops (:func:`trace`); the stops are placed on that trace by
their nearest point. On P2 the straight line crosses a terrace and a step
that the blocks' corridor avoids (docs/calibration.md, "Why P2 was not
predicted").

Coordinates in the dataset: x and z horizontal, y up (m). The stop positions
lie about 2.8 m above the terrain surface beneath them (on the benches and
the floor alike), a constant offset of the survey; only their positions on
the map are used here.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path

import numpy as np
import yaml

#: The terrain's zones (file stem) and the material of a segment over each.
ZONES = (("DTM_Blue_zone", "vegetated"), ("DTM_Gray_zone", "floor"), ("DTM_Red_zone", "rocky"))

#: Starting values: the textbook values of issue 23 (soil for the vegetated
#: slope, rock for everything else); calibrate fits some of them.
STARTING_MATERIALS = """\
# Starting values for the Authume quarry projects (textbook values, not fitted):
# the vegetated slope as a soil, walls, benches, floor and rocky slopes as rock.
vegetated: {restitution: 0.3, friction: 0.6, rolling_resistance: 0.4, roughness_deg: 4}
wall: {restitution: 0.5, friction: 0.5, rolling_resistance: 0.15, roughness_deg: 8}
floor: {restitution: 0.5, friction: 0.5, rolling_resistance: 0.15, roughness_deg: 8}
rocky: {restitution: 0.5, friction: 0.5, rolling_resistance: 0.15, roughness_deg: 8}
"""

#: The fitted inputs and their ranges: the restitution and rolling resistance
#: of the vegetated slope (how fast the blocks reach the wall) and of the
#: benches and the floor (where they stop). Wide ranges: with the textbook
#: values nearly every simulated rock leaves the section, and the fit needs
#: room to find where the sphere stops where the blocks did.
FIT = {"materials.vegetated.restitution": [0.0, 0.7],
       "materials.vegetated.rolling_resistance": [0.05, 3.0],
       "materials.floor.restitution": [0.0, 0.7],
       "materials.floor.rolling_resistance": [0.05, 3.0]}


#: ``--law rough_soft``: the bundled library's ``ground_`` class of each role
#: (docs/materials.md): the vegetated slope, the walls, the benches and the
#: quarry floor (compact, Rockyfor3D soil type 5), the rocky slopes.
GROUND_CLASSES = {"vegetated": "ground_vegetated_slope", "wall": "ground_rock_face",
                  "floor": "ground_hard_floor", "rocky": "ground_talus"}

#: The bundled materials library the ``ground_`` classes are copied from.
LIBRARY = Path(__file__).resolve().parents[1] / "projects" / "materials.yaml"

def ground_library(library: Path = LIBRARY) -> str:
    """The roles' materials as a library: each a copy of its ``ground_`` class."""
    entries = yaml.safe_load(library.read_text(encoding="utf-8"))
    lines = ["# The Authume roles as the bundled library's ground_ classes (rough_soft law),",
             f"# copied from {library.name} by examples/authume_quarry.py --law rough_soft.",
             "# Their values are those of the library: ILLUSTRATIVE (see its sources)."]
    for role, cls in GROUND_CLASSES.items():
        lines.append(f"# {role}: copy of {cls}")
        lines.append(yaml.safe_dump({role: entries[cls]}, sort_keys=False,
                                    default_flow_style=None).rstrip())
    return "\n".join(lines) + "\n"


def read_stl(path: Path) -> np.ndarray:
    """Triangles (n, 3, 3) of an ASCII STL file (x, y, z of each vertex)."""
    values = [line.split()[1:4] for line in path.read_text(encoding="utf-8").splitlines()
              if line.strip().startswith("vertex")]
    if not values or len(values) % 3:
        raise SystemExit(f"{path}: not an ASCII STL surface")
    return np.asarray(values, dtype=float).reshape(-1, 3, 3)


def surface_height(triangles: np.ndarray, zone: np.ndarray, points: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Height (y) of the surface above map points (x, z), and the zone hit there.

    The highest triangle over each point (a wall's triangles are nearly
    vertical and do not hide the ground). NaN and -1 where no triangle is.
    """
    a = triangles[:, 0, :][:, [0, 2]]
    e0 = triangles[:, 1, :][:, [0, 2]] - a
    e1 = triangles[:, 2, :][:, [0, 2]] - a
    d00, d01, d11 = (e0 * e0).sum(1), (e0 * e1).sum(1), (e1 * e1).sum(1)
    den = d00 * d11 - d01 * d01
    flat = np.abs(den) > 1e-12  # a vertical triangle has no area on the map
    heights = np.full(len(points), np.nan)
    zones = np.full(len(points), -1)
    for i, p in enumerate(points):
        r = p - a
        d20, d21 = (r * e0).sum(1), (r * e1).sum(1)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = (d11 * d20 - d01 * d21) / den
            w = (d00 * d21 - d01 * d20) / den
        u = 1.0 - v - w
        hit = flat & (u >= -1e-9) & (v >= -1e-9) & (w >= -1e-9)
        if hit.any():
            y = (u[hit] * triangles[hit, 0, 1] + v[hit] * triangles[hit, 1, 1]
                 + w[hit] * triangles[hit, 2, 1])
            k = int(np.argmax(y))
            heights[i], zones[i] = y[k], zone[hit][k]
    return heights, zones


def simplify(x: np.ndarray, y: np.ndarray, keep: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the points kept (Douglas-Peucker on the section; ``keep`` always kept)."""
    chosen = np.zeros(len(x), dtype=bool)
    chosen[[0, -1]] = True
    chosen |= keep
    stack = [(0, len(x) - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        t = (x[i + 1:j] - x[i]) / (x[j] - x[i])
        dev = np.abs(y[i + 1:j] - (y[i] + t * (y[j] - y[i])))
        k = i + 1 + int(np.argmax(dev))
        if dev.max() > tolerance:
            chosen[k] = True
        inner = [m for m in range(i + 1, j) if chosen[m]]
        bounds = [i, *inner, j]
        if inner:
            stack.extend(zip(bounds[:-1], bounds[1:], strict=True))
    return np.flatnonzero(chosen)


def fall_line(triangles: np.ndarray, zone: np.ndarray, start: np.ndarray,
              args: argparse.Namespace) -> np.ndarray:
    """Map points (n, 2) of the fall line from ``start`` down to the first flat ground.

    Each step of ``args.step`` m goes down the surface's steepest descent,
    its gradient taken by central differences over ``args.baseline`` m (which
    smooths the mesh's facets); the line ends where the ground is gentler
    than ``args.flat_deg`` degrees (the first bench or floor: on flat ground
    a block keeps the heading it came with rather than following the
    terrain) or leaves the terrain. A block rolling or sliding down a slope
    follows its fall line (Dorren 2003, "modes of motion"); on the Authume
    terrain this line runs within about 1.5 m of the median path of the
    dataset's own 3-D simulations over P2's upper slope (docs/calibration.md).
    """
    b = args.baseline
    probe = np.array([[b, 0.0], [-b, 0.0], [0.0, b], [0.0, -b]])
    points = [np.asarray(start, dtype=float)]
    for _ in range(int(400.0 / args.step)):
        h, _ = surface_height(triangles, zone, points[-1] + probe)
        if not np.all(np.isfinite(h)):
            break
        grad = np.array([h[0] - h[1], h[2] - h[3]]) / (2.0 * b)
        steep = float(np.hypot(*grad))
        if math.degrees(math.atan(steep)) < args.flat_deg:
            break
        points.append(points[-1] - args.step * grad / steep)
    return np.asarray(points)


def trace(triangles: np.ndarray, zone: np.ndarray, origin: np.ndarray, target: np.ndarray,
          args: argparse.Namespace) -> np.ndarray:
    """The section's trace on the map: a polyline (n, 2) from upslope of ``origin``.

    ``--trace line``: the straight line from the drop point ``origin`` to
    ``target`` (the middle of the stops), from ``--upslope`` m above the
    drop point to 400 m beyond it. ``--trace fall-line``: the same start, then
    the fall line from the drop point (:func:`fall_line`) to the first flat
    ground, then straight to ``target`` and on beyond it.
    """
    u = (target - origin) / np.linalg.norm(target - origin)
    head = origin - args.upslope * u
    if args.trace == "line":
        return np.array([head, origin + 400.0 * u])
    down = fall_line(triangles, zone, origin, args)
    foot = down[-1]
    ahead = target - foot
    if np.linalg.norm(ahead) < args.step or ahead @ u <= 0.0:
        ahead = u  # the fall line ends at or beyond the stops: keep the line's heading
    ahead = ahead / np.linalg.norm(ahead)
    tail = [target] if (target - foot) @ ahead > args.step else []
    end = (tail[0] if tail else foot) + 400.0 * ahead
    return np.array([head, *down, *tail, end])


def along(poly: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Arc length s (m) every ``step`` m along a polyline, and the map points there."""
    seg = np.hypot(*np.diff(poly, axis=0).T)
    cum = np.r_[0.0, np.cumsum(seg)]
    s = np.arange(0.0, cum[-1], step)
    return s, np.c_[np.interp(s, cum, poly[:, 0]), np.interp(s, cum, poly[:, 1])]


def onto(poly: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Arc length (m) of each map point's nearest point on a polyline, and its offset (m).

    The offset is signed, positive to the left of the trace's direction.
    """
    a, b = poly[:-1], poly[1:]
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    cum = np.r_[0.0, np.cumsum(length)]
    rel = points[:, None, :] - a[None, :, :]
    t = np.clip((rel * d[None]).sum(-1) / length**2, 0.0, 1.0)
    gap = rel - t[..., None] * d[None]
    k = np.argmin(np.hypot(gap[..., 0], gap[..., 1]), axis=1)
    i = np.arange(len(points))
    side = np.sign(d[k, 0] * rel[i, k, 1] - d[k, 1] * rel[i, k, 0])
    return cum[k] + t[i, k] * length[k], side * np.hypot(gap[i, k, 0], gap[i, k, 1])


def profile(data: Path, name: str, triangles: np.ndarray, zone: np.ndarray,
            args: argparse.Namespace) -> dict:
    """The section, the stops and the release of one profile (``P1`` or ``P2``)."""
    drops = np.loadtxt(data / "Drop_conditions" / f"positions_{name}.xyz", ndmin=2)
    ends = np.loadtxt(data / "EXP_endpoints" / f"Endpoints_{name}.txt", ndmin=2)
    origin = drops[:, [0, 2]].mean(0)
    target = ends[:, [0, 2]].mean(0)
    u = (target - origin) / np.linalg.norm(target - origin)
    poly = trace(triangles, zone, origin, target, args)
    s, points = along(poly, args.step)
    h, z = surface_height(triangles, zone, points)
    inside = np.flatnonzero(np.isfinite(h))
    first = inside[0]
    last = first + np.flatnonzero(np.diff(np.r_[inside, -9]) != 1)[0]  # first gap ends it
    s, h, z = s[first:last + 1], h[first:last + 1], z[first:last + 1]
    x = s - s[0]
    steep = np.degrees(np.arctan2(np.abs(np.diff(h)), np.diff(x))) > args.wall_deg
    names = [ZONES[k][1] if k >= 0 else "floor" for k in z[:-1]]
    names = ["wall" if st else n for st, n in zip(steep, names, strict=True)]
    change = np.r_[True, np.array(names[1:]) != np.array(names[:-1]), True]
    idx = simplify(x, h, change, args.tolerance)
    seg = [names[i] for i in idx[:-1]]
    stations, offsets = onto(poly, ends[:, [0, 2]])
    drop_x = onto(poly, drops[:, [0, 2]])[0] - s[0]
    ground = float(np.interp(drop_x.mean(), x, h))
    return {"x": x[idx], "y": h[idx], "materials": seg, "stops": stations - s[0],
            "offset": offsets, "mass": ends[:, 3],
            "release_x": (float(drop_x.min()), float(drop_x.max())),
            "release_height": float(drops[:, 1].mean() - ground), "heading_deg":
            math.degrees(math.atan2(u[1], u[0])), "trace": poly}


def levels(p: dict, shortest: float = 3.5) -> dict[str, list[float]]:
    """The section's levels: each run of one material between walls, [from, to) (m).

    Runs shorter than ``shortest`` (the lip of a wall) are left out. Names:
    the vegetated runs ``slope``, ``lower_slope``, ...; the flat hard runs
    ``bench``, ``bench_2``, ... and the last of them ``floor``; a rocky run
    ``rocky``.
    """
    x, mats = p["x"], p["materials"]
    runs: list[tuple[str, float, float]] = []
    i = 0
    while i < len(mats):
        j = i
        while j + 1 < len(mats) and mats[j + 1] == mats[i]:
            j += 1
        if mats[i] != "wall" and x[j + 1] - x[i] >= shortest:
            runs.append((mats[i], round(float(x[i]), 2), round(float(x[j + 1]), 2)))
        i = j + 1
    floors = [r for r in runs if r[0] == "floor"]
    out: dict[str, list[float]] = {}
    seen: dict[str, int] = {}
    for kind, lo, hi in runs:
        if kind == "floor":
            base = "floor" if (kind, lo, hi) == floors[-1] else "bench"
        else:
            base = {"vegetated": "slope", "rocky": "rocky"}.get(kind, kind)
        seen[base] = seen.get(base, 0) + 1
        n = seen[base]
        name = base if n == 1 else ("lower_" + base if base == "slope" and n == 2
                                    else f"{base}_{n}")
        out[name] = [lo, hi]
    return out


def project_text(name: str, p: dict, materials: str, seed: int, calibrate: bool,
                 fit: dict | str | None = None) -> str:
    """The project file of profile ``name`` (section, materials library, rocks, calibrate:).

    ``calibrate=False``: a project to ``compare`` with (its ``calibrate:``
    section still gives the levels and the observed file). ``fit``: the
    inputs fitted and their ranges (default :data:`FIT`), or ``"auto"``.
    """
    lv = levels(p)
    lines = [
        f"# Authume quarry, profile {name}: written by examples/authume_quarry.py from the",
        "# published tests (Garcia et al.; data: github.com/richefeu/AuthumeQuarryRockfalls_"
        "Data-in-Brief).",
        f"name: Authume quarry {name}",
        f"description: Full-scale tests, profile {name}; section cut "
        + ("along the fall line from the drop point, then towards the stops, "
           if len(p["trace"]) > 2 else "along ")
        + f"heading {p['heading_deg']:.1f} deg of the dataset's x-z plane.",
        "slope:",
        f"  csv: section_{name}.csv",
        "materials:",
        f"  library: {materials}",
        "rocks:",
        "  count: 1000",
        f"  seed: {seed}",
        "  density: 2600",
        "  mass: 800                          # kg; calibrate and compare take the observed masses",
        f"  release: {{x: [{p['release_x'][0]:.2f}, {p['release_x'][1]:.2f}], height: "
        f"{p['release_height']:.2f}, velocity: [0, 0]}}",
    ]
    lines.append("calibrate:")
    lines.append(f"  observed: stops_{name}.csv")
    if fit == "auto":
        lines.append("  fit: auto")
    else:
        lines.append("  fit:")
        lines += [f"    {k}: [{lo:g}, {hi:g}]" for k, (lo, hi) in (fit or FIT).items()]
    lines.append("  levels: {" + ", ".join(f"{k}: [{lo:g}, {hi:g}]" for k, (lo, hi)
                                           in lv.items()) + "}")
    lines.append("  rocks: 500")
    lines.append("  bootstrap: 40")
    if not calibrate:
        lines.insert(0, "# compare only: its calibrate: section gives the levels and the "
                        "observed file")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", type=Path, help="the user's copy of the dataset (a clone of "
                    "github.com/richefeu/AuthumeQuarryRockfalls_Data-in-Brief)")
    ap.add_argument("out", type=Path, help="folder to write the sections, stops and projects")
    ap.add_argument("--step", type=float, default=0.5,
                    help="station step of the cut (m, default 0.5)")
    ap.add_argument("--tolerance", type=float, default=0.1,
                    help="simplification of the section (m, default 0.1)")
    ap.add_argument("--wall-deg", type=float, default=50.0,
                    help="segments steeper than this are wall (degrees, default 50)")
    ap.add_argument("--split-seed", type=int, default=2023,
                    help="seed of the random split of P1's blocks into halves (default 2023)")
    ap.add_argument("--upslope", type=float, default=4.0,
                    help="the section starts this far upslope of the drop point (m, default 4)")
    ap.add_argument("--trace", choices=("line", "fall-line"), default="line",
                    help="the section's trace on the map: line (straight from the drop "
                    "point to the middle of the stops, default) or fall-line (down the "
                    "terrain's fall line from the drop point to the first flat ground, then "
                    "straight to the middle of the stops)")
    ap.add_argument("--flat-deg", type=float, default=10.0,
                    help="--trace fall-line: the fall line ends on ground gentler than "
                    "this (degrees, default 10)")
    ap.add_argument("--baseline", type=float, default=2.0,
                    help="--trace fall-line: the surface's gradient is taken over this "
                    "distance (m, default 2)")
    ap.add_argument("--law", choices=("spang", "rough_soft"), default="spang",
                    help="materials of the projects: spang (the textbook starting values, "
                    "default) or rough_soft (the bundled library's ground_ classes by role, "
                    "calibrate: fit: auto)")
    args = ap.parse_args(argv)

    files = [args.data / "Geometries" / "STL" / f"{stem}.stl" for stem, _ in ZONES]
    missing = [f for f in files if not f.is_file()]
    if missing:
        sys.stderr.write(f"{missing[0]}: not found (give the folder of the dataset's "
                         "clone)\n")
        return 2
    parts = [read_stl(f) for f in files]
    triangles = np.concatenate(parts)
    zone = np.concatenate([np.full(len(t), k) for k, t in enumerate(parts)])
    args.out.mkdir(parents=True, exist_ok=True)
    if args.law == "rough_soft":
        start = "ground_materials.yaml"
        (args.out / start).write_text(ground_library(), encoding="utf-8")
    else:
        start = "starting_materials.yaml"
        (args.out / start).write_text(STARTING_MATERIALS, encoding="utf-8")
    for seed, name in enumerate(("P1", "P2"), start=1):
        p = profile(args.data, name, triangles, zone, args)
        with open(args.out / f"section_{name}.csv", "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(["x", "y", "material"])
            for i, (xi, yi) in enumerate(zip(p["x"], p["y"], strict=True)):
                w.writerow([f"{xi:.2f}", f"{yi:.3f}",
                            p["materials"][i] if i < len(p["x"]) - 1 else ""])
        rows = [[f"{xi:.2f}", f"{m:g}", f"{off:.1f}"]
                for xi, m, off in zip(p["stops"], p["mass"], p["offset"], strict=True)]
        files = {f"stops_{name}.csv": rows}
        if name == "P1":  # halves by block, drawn from a seeded generator
            order = np.random.default_rng(args.split_seed).permutation(len(rows))
            half = len(rows) // 2
            files["stops_P1_a.csv"] = [rows[i] for i in sorted(order[half:])]
            files["stops_P1_b.csv"] = [rows[i] for i in sorted(order[:half])]
        for file, part in files.items():
            with open(args.out / file, "w", newline="", encoding="utf-8") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(["x", "mass_kg", "offset_m"])
                w.writerows(part)
        fit = "auto" if args.law == "rough_soft" else None
        (args.out / f"authume_{name}.yaml").write_text(
            project_text(name, p, start, seed, True, fit), encoding="utf-8")
        (args.out / f"authume_{name}_calibrated.yaml").write_text(
            project_text(name, p, "calibrated_materials.yaml", seed, False, fit),
            encoding="utf-8")
        sys.stdout.write(
            f"{name}: section of {len(p['x'])} points over {p['x'][-1]:.1f} m; "
            f"{len(p['stops'])} stops from {p['stops'].min():.1f} to {p['stops'].max():.1f} m, "
            f"up to {np.abs(p['offset']).max():.1f} m from the line on the map; levels "
            f"{levels(p)}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
