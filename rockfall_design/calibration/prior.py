"""The literature as the prior of a calibration: a regularised (maximum a posteriori) fit.

``fit: auto`` fits each material's calibrated parameters within its class's
published range (``ranges:``, docs/materials.md). Used as bounds alone, a
range lets a parameter the observations do not pin down go anywhere in it
from one bootstrap refit to the next. Used as a prior, it keeps such a
parameter near the class's value, and lets the observations move what they
do identify. The fit then minimises::

    D(theta) + s_D * sum_j z_j**2

with D the calibration's criterion (:func:`~.distances.objective`,
:func:`~.terms.sets_objective`), z_j the distance of parameter j from its
class's value c_j in prior standard deviations, and s_D the criterion's own
sampling noise (:func:`criterion_noise`).

The prior of a parameter is a two-piece normal with its mode at the class's
value and the range's ends at two standard deviations on either side
(sigma_low = (c - low) / 2, sigma_high = (high - c) / 2): the range holds
about 95 % of the prior, and a value placed off the range's centre keeps its
place. The weight: D is not a log-likelihood, so how much a unit of D
weighs against a unit of the prior must be set. One change of D by its own
sampling standard deviation s_D is what a different draw of the observed
blocks (and of the simulated rocks) makes of it: differences below s_D the
observations cannot resolve. Counting a change of D by s_D as one unit of
-2 log-likelihood (a one-sigma change, as one unit of chi-square is) gives
the posterior exp(-D / (2 s_D)) * prior, a generalised-Bayes ("Gibbs")
posterior with learning rate 1 / s_D, whose mode is the minimum above.
Along a direction that D does not see (a ridge, a parameter that moves no
share) the prior decides; across one that D sees, a change of D by k s_D
outweighs a shift of the parameter by sqrt(k) prior standard deviations.

References
----------
Tarantola, A. (2005). Inverse Problem Theory and Methods for Model
Parameter Estimation. SIAM, ch. 3 (the maximum a posteriori point of a
least-squares misfit with a Gaussian prior).
Bissiri, P. G., Holmes, C. C., Walker, S. G. (2016). A general framework for
updating belief distributions. J. R. Stat. Soc. B 78(5), 1103-1130 (a loss
in place of the likelihood, and its weight).
Fischer, J.-T., Kofler, A., Huber, A., Fellin, W., Mergili, M.,
Oberguggenberger, M. (2020). Bayesian inference in snow avalanche
simulation with r.avaflow. Geosciences 10(5), 191 (Bayesian back-analysis of
a gravitational mass-flow model's friction parameters).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..studies.paths import parse_path
from .distances import objective
from .terms import Term, sets_objective

__all__ = ["HELD_BY_PRIOR_SHARE", "NULL_DRAWS", "PRIOR_SIGMAS", "criterion_noise",
           "posterior_shares", "prior_centres", "prior_penalty", "prior_sds"]

#: The range's ends lie this many prior standard deviations from the class's value.
PRIOR_SIGMAS = 2.0
#: Draws of the criterion under a model that is right (:func:`criterion_noise`):
#: its standard deviation to about 5 % (1 / sqrt(2 (N - 1))).
NULL_DRAWS = 200


def prior_centres(base: Mapping[str, Any], fit_ranges: Mapping[str, tuple[float, float]]
                  ) -> tuple[float, ...]:
    """Each fitted input's value in ``base`` (the class's value): the prior's mode.

    Parameters
    ----------
    base
        The project's resolved data (materials from their library resolved).
    fit_ranges
        Path -> (low, high); each path's value lies in its range (the
        ``ranges:`` of a material hold its value, checked on reading).

    Raises
    ------
    ValueError
        A path without a number in ``base`` or its value outside its range.
    """
    out = []
    for path, (lo, hi) in fit_ranges.items():
        node: Any = base
        for key in parse_path(path):
            try:
                node = node[key]
            except (KeyError, IndexError, TypeError):
                node = None
                break
        if not isinstance(node, (int, float)) or not lo <= float(node) <= hi:
            raise ValueError(f"{path}: the prior needs the project's value inside the "
                             f"range [{lo:g}, {hi:g}], found {node!r}")
        out.append(float(node))
    return tuple(out)


def prior_penalty(theta: Sequence[float], centre: Sequence[float], low: Sequence[float],
                  high: Sequence[float]) -> float:
    """sum_j z_j**2: the squared distances of ``theta`` from ``centre`` in prior sds (-).

    A two-piece normal per input (the module's docstring): below its value
    sigma = (c - low) / :data:`PRIOR_SIGMAS`, above it (high - c) / PRIOR_SIGMAS.
    A side of zero width (the value at an end of its range) adds nothing:
    the bound keeps the input there.
    """
    t, c = np.asarray(theta, dtype=float), np.asarray(centre, dtype=float)
    side = np.where(t < c, c - np.asarray(low, dtype=float), np.asarray(high, dtype=float) - c)
    sigma = side / PRIOR_SIGMAS
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(sigma > 0.0, (t - c) / sigma, 0.0)
    return float(np.sum(z * z))


def criterion_noise(observed: Sequence[np.ndarray], terms: Sequence[Term], kind: str,
                    scales: Sequence[float], rocks: int, seed: int,
                    single: Mapping[str, tuple[float, float]] | None = None) -> float:
    """s_D: the standard deviation of the criterion when the model is right (-).

    The criterion's sampling noise at a perfect fit, from the observations
    alone: every set's observed values stand for the true distribution; the
    observed values are drawn from it (n of them, with replacement), the
    simulated ones too (``rocks`` of them), and the criterion is measured
    between the two, :data:`NULL_DRAWS` times. Nothing is simulated, so it
    costs no engine run, and it holds both the noise of which blocks were
    observed and that of which rocks were simulated.

    Parameters
    ----------
    observed
        Each set's observed values (m or m/s).
    terms
        Their terms (kind, weight, levels).
    kind
        The distance (:func:`~.distances.distance`).
    scales
        Each term's L (:func:`~.terms.scales_of`).
    rocks
        Simulated rocks per evaluation.
    seed
        Of the draws (a generator of its own, apart from the rocks').
    single
        The single-file form's levels (its criterion is
        :func:`~.distances.objective` with them); None with observation sets.

    References
    ----------
    Efron, B., Tibshirani, R. J. (1993). An Introduction to the Bootstrap.
    Chapman & Hall, ch. 16 (resampling under the null hypothesis).
    """
    rng = np.random.default_rng([int(seed), 35])
    values = np.empty(NULL_DRAWS)
    for i in range(NULL_DRAWS):
        obs = [rng.choice(o, size=o.size, replace=True) for o in observed]
        sim = [rng.choice(o, size=int(rocks), replace=True) for o in observed]
        if single is not None:
            values[i] = objective(obs[0], sim[0], single, kind, scales[0])
        else:
            values[i] = sets_objective(obs, sim, terms, kind, scales)
    return float(values.std(ddof=1))


#: An input whose posterior standard deviation keeps more than this share of
#: its prior one is held by the prior, not pinned down by the observations:
#: 1 / sqrt(2), where the observations and the prior carry the same
#: information on it (their precisions equal, the posterior variance half
#: the prior's).
HELD_BY_PRIOR_SHARE = 2.0**-0.5


def prior_sds(u: Sequence[float], centre: Sequence[float], low: Sequence[float],
              high: Sequence[float]) -> np.ndarray:
    """Each input's prior sd as a share of its range, on the side of ``u`` (unit cube).

    A side of zero width (the value at an end of its range) takes the other side's.
    """
    lo, hi = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    c = (np.asarray(centre, dtype=float) - lo) / np.where(hi > lo, hi - lo, 1.0)
    x = np.asarray(u, dtype=float)
    below, above = c, 1.0 - c
    side = np.where(x < c, below, above)
    side = np.where(side > 0.0, side, np.maximum(below, above))
    return side / PRIOR_SIGMAS


def posterior_shares(f: Callable[[np.ndarray], float], u: Sequence[float],
                     sigma: Sequence[float], noise: float) -> np.ndarray:
    """Each input's posterior sd over its prior sd (Laplace approximation at ``u``), 0..1.

    Parameters
    ----------
    f
        The criterion D of a point of the unit cube (common random numbers).
    u
        The best point (unit cube).
    sigma
        Each input's prior sd in the unit cube (:func:`prior_sds`).
    noise
        s_D (:func:`criterion_noise`).

    Notes
    -----
    In prior units z (z_j = (theta_j - c_j) / sigma_j) the posterior is
    ``-2 log p = D / s_D + |z|**2``; its Hessian at the best point is
    ``H + 2 I`` with H that of D / s_D, so the posterior covariance is
    ``2 (H + 2 I)**-1`` and the prior's is I. H is taken by central finite
    differences with a step of one prior sd (at most half the range), the
    stencil moved inside the cube where the best point lies near a bound,
    and its negative eigenvalues (noise) set to 0. The full matrix is
    inverted, so a ridge (two inputs that trade off) leaves both of them
    with a wide posterior though each one alone moves D. 1 + 2 d**2
    evaluations for d inputs.

    References
    ----------
    Tarantola, A. (2005). Inverse Problem Theory and Methods for Model
    Parameter Estimation. SIAM, sec. 3.2 (the posterior covariance of a
    linearised problem with a Gaussian prior).
    """
    s = np.minimum(np.asarray(sigma, dtype=float), 0.5)
    d = s.size
    c = np.clip(np.asarray(u, dtype=float), s, 1.0 - s)
    eye = np.eye(d)

    def at(*steps: tuple[int, float]) -> float:
        x = c.copy()
        for j, sign in steps:
            x = x + sign * s[j] * eye[j]
        return float(f(x))

    f0 = at()
    h = np.zeros((d, d))
    for i in range(d):
        h[i, i] = at((i, 1.0)) - 2.0 * f0 + at((i, -1.0))
        for j in range(i):
            h[i, j] = h[j, i] = (at((i, 1.0), (j, 1.0)) - at((i, 1.0), (j, -1.0))
                                 - at((i, -1.0), (j, 1.0)) + at((i, -1.0), (j, -1.0))) / 4.0
    # Steps of one prior sd: h is already the Hessian in prior units, of D.
    w, v = np.linalg.eigh(h / max(noise, 1e-12))
    hz = (v * np.clip(w, 0.0, None)) @ v.T
    cov = 2.0 * np.linalg.inv(hz + 2.0 * eye)
    return np.sqrt(np.clip(np.diag(cov), 0.0, 1.0))
