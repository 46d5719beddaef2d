"""A quick screen before a ``fit: auto``: leave out what moves the criterion by less than its noise.

``fit: auto`` names every material's calibrated parameters; some of them the
observations cannot see at all (on Authume P1 the walls' rolling resistance:
the rocks fly off the walls, and its class's range moves no level's share).
Fitting such an input costs evaluations and, without a prior, lets it wander
over its range from one bootstrap refit to the next. The screen runs the
engine at the classes' values (the prior's modes), then with each input at
either end of its range, the others at their values (one at a time, the
rocks of the calibration's seed: common random numbers), and leaves out an
input whose two ends move the criterion D by less than its sampling noise
s_D (:func:`~.prior.criterion_noise`): the observations cannot tell its
ends apart there. It keeps its class's value, and the output says so.

One at a time from the classes' values is a local screen (Saltelli et al.
2008, ch. 1, on one-at-a-time designs): an input that acts only together
with another, or only far from the classes' values, can be missed. When the
screen finds no input that moves D (the classes' values far from the
observations, where nothing responds), it says nothing and every input is
fitted.

References
----------
Saltelli, A., Ratto, M., Andres, T., et al. (2008). Global Sensitivity
Analysis. The Primer. Wiley, ch. 1 and 3.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .fit import FitProblem, criterion_for, simulated_sets

__all__ = ["Screened", "screen"]


@dataclass(frozen=True)
class Screened:
    """One input the screen measured.

    Attributes
    ----------
    path : str
    value : float
        Its class's value (the input's unit), where it stays if left out.
    range : tuple of float
        Its range (the input's unit).
    effect : float
        The largest change of D with the input at an end of its range (-).
    noise : float
        s_D (-).
    kept : bool
        Whether it is fitted (``effect`` at least ``noise``).
    """

    path: str
    value: float
    range: tuple[float, float]
    effect: float
    noise: float
    kept: bool

    def to_json(self) -> dict[str, Any]:
        """The entry of ``method.screen`` in ``calibrate --json``."""
        return {"path": self.path, "value": self.value, "range": list(self.range),
                "effect": self.effect, "noise": self.noise, "kept": self.kept}

    @property
    def line(self) -> str:
        """The sentence the output gives an input left out."""
        return (f"{self.path}: left out of the fit and kept at its class's value "
                f"{self.value:g} (over its range [{self.range[0]:g}, {self.range[1]:g}] it "
                f"moves the criterion by at most {self.effect:.3g}, less than its sampling "
                f"noise {self.noise:.3g}: the observations cannot see it; --no-screen fits it)")


def screen(problem: FitProblem, observed: np.ndarray | Sequence[np.ndarray], seed: int
           ) -> list[Screened]:
    """Each input's effect on D over its range, one at a time from the prior's modes.

    Parameters
    ----------
    problem
        A regularised problem (``problem.prior`` gives the classes' values).
    observed
        As :func:`~.fit.fit`'s.
    seed
        The rocks' seed of every run (the calibration's).

    Returns
    -------
    list of Screened
        In the order of ``problem.paths``; every one ``kept`` when none moves D
        by its noise (the module's docstring). 1 + 2 d engine runs.
    """
    value, noise = criterion_for(problem, observed, seed, with_noise=True)
    assert noise is not None
    centre = dict(zip(problem.paths, problem.prior, strict=True))
    d0 = value(simulated_sets(problem, centre, seed))
    out = []
    for path, lo, hi in zip(problem.paths, problem.low, problem.high, strict=True):
        effect = max(abs(value(simulated_sets(problem, {**centre, path: end}, seed)) - d0)
                     for end in (lo, hi))
        out.append(Screened(path, centre[path], (lo, hi), float(effect), noise,
                            bool(effect >= noise)))
    if not any(s.kept for s in out):
        out = [Screened(s.path, s.value, s.range, s.effect, s.noise, True) for s in out]
    return out
