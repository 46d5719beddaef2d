"""Small builders shared by the engine tests."""

from __future__ import annotations

import numpy as np

from rockfall_design.engine import Material, Releases, Section, run_ensemble


def section(points, material: Material) -> Section:
    pts = np.asarray(points, dtype=float)
    return Section(pts[:, 0], pts[:, 1], np.zeros(len(pts) - 1, dtype=int), (material,))


def one_rock(
    r: float = 0.5,
    x: float = 0.0,
    h: float = 0.0,
    vx: float = 0.0,
    vy: float = 0.0,
    w: float = 0.0,
    rolling: bool = False,
    density: float = 2650.0,
    n: int = 1,
) -> Releases:
    def f(v):
        return np.full(n, v, dtype=float)

    return Releases(
        radius=f(r),
        density=density,
        x=f(x),
        height=f(h),
        vx=f(vx),
        vy=f(vy),
        spin=f(w),
        spin_rolling=np.full(n, rolling),
    )


def run_one(sec: Section, rel: Releases, stations=(), key: int = 1, **kw):
    return run_ensemble(sec, rel, key=key, stations=stations, n_trajectories=len(rel), **kw)
