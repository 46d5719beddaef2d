"""``rockfall-design section``: a slope section cut from a DEM, for inspection.

    rockfall-design section terrain.tif --fall-line E,N --out section.csv --plot section.png
    rockfall-design section terrain.tif --line E1,N1 E2,N2 ... --out section.csv

writes the section as a survey CSV (x, y; ``slope: {csv: section.csv}``
reads it) and, with ``--plot``, its profile beside its line on the
hillshaded DEM. Needs the extra ``[terrain]``.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

import numpy as np

from ..api import cut_section, read_dem, trace_fall_line
from ..errors import ExitCode, InputError
from ..report.outputs import OutputSet
from ..results import Dem, TerrainSection

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["cmd_section", "section_figure"]

#: The figure formats of --plot (those of every other command's --plot-format).
PLOT_SUFFIXES = (".png", ".svg", ".pdf")


def cmd_section(args: argparse.Namespace) -> int:
    """Cut the section, write its CSV (and figure), print one line about it."""
    if args.line is not None and len(args.line) < 2:
        raise InputError("--line needs two or more points E,N")
    if args.stop is not None and len(args.stop) < 2:
        raise InputError("--stop needs two or more points E,N")
    if args.spacing is not None and args.spacing <= 0:
        raise InputError("--spacing must be > 0")
    if args.plot is not None and args.plot.suffix.lower() not in PLOT_SUFFIXES:
        raise InputError(f"--plot {args.plot}: expected a file ending in "
                         f"{', '.join(PLOT_SUFFIXES)}")
    dem = read_dem(args.dem)
    how = "along the line"
    if args.fall_line is not None:
        path = trace_fall_line(dem, args.fall_line, flat_deg=args.flat_deg,
                               stop_line=None if args.stop is None else np.array(args.stop))
        section = cut_section(dem, path.points, spacing=args.spacing, tolerance=args.tolerance,
                              what="the fall line", vertices=False, orient=False)
        how = f"down the fall line (ends: {path.stop})"
    else:
        section = cut_section(dem, np.array(args.line), spacing=args.spacing,
                              tolerance=args.tolerance, what="--line")
    lines = [f"# section of {args.dem} {how}; vertical tolerance {args.tolerance:g} m",
             f"# starts at E {section.line_e[0]:.2f}, N {section.line_n[0]:.2f}; "
             f"ends at E {section.line_e[-1]:.2f}, N {section.line_n[-1]:.2f}", "x,y"]
    lines += [f"{x:.4f},{y:.4f}" for x, y in section.points()]
    with OutputSet() as files:
        files.reserve(args.out, *([args.plot] if args.plot else []))
        files.write_text(args.out, "\n".join(lines) + "\n")
        if args.plot:
            fig = section_figure(dem, section, f"{args.dem.name}: section {how}")
            fmt = args.plot.suffix.lstrip(".").lower() or "png"
            files.write_with(args.plot, lambda fh: fig.savefig(fh, format=fmt, dpi=150,
                                                               bbox_inches="tight"))
    drop = section.z[0] - section.z[-1]
    sys.stdout.write(f"{args.out}: {len(section.x)} points, {section.x[-1]:.1f} m long, "
                     f"{drop:.1f} m drop, {how}\n")
    return int(ExitCode.OK)


def section_figure(dem: Dem, section: TerrainSection, title: str) -> Figure:
    """The section's profile (samples and simplified) beside its line on the map."""
    # matplotlib is heavy (a fifth of a second): loaded only to draw, not for every command.
    from matplotlib.colors import LightSource
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.5))
    profile, plan = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.6, 1]})
    profile.plot(section.dense_x, section.dense_z, color="0.6", lw=2.5, label="DEM samples")
    profile.plot(section.x, section.z, color="black", lw=1, marker=".", ms=3,
                 label=f"section ({len(section.x)} points)")
    profile.set_xlabel("x along the line (m)")
    profile.set_ylabel("height (m)")
    profile.set_aspect("equal", adjustable="datalim")
    profile.legend(fontsize=8)
    e0, e1, n0, n1 = dem.extent
    shade = LightSource(315, 45).hillshade(np.nan_to_num(dem.z, nan=float(np.nanmin(dem.z))),
                                           dx=dem.dx, dy=dem.dy)
    plan.imshow(shade, cmap="gray", origin="upper",
                extent=(e0 - dem.dx / 2, e1 + dem.dx / 2, n0 - dem.dy / 2, n1 + dem.dy / 2))
    plan.plot(section.line_e, section.line_n, color="crimson", lw=1.5)
    plan.plot(section.line_e[:1], section.line_n[:1], "o", color="crimson", ms=4)
    plan.set_aspect("equal")
    plan.ticklabel_format(useOffset=False, style="plain")
    plan.tick_params(labelsize=6)
    fig.suptitle(title, fontsize=10)
    return fig
