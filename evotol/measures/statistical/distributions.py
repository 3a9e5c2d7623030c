"""Statistical distributions of the error sources inside their tolerances, per unit tolerance.

A source j with tolerance t_j has an error vector e_j = t_j · z_j, where z_j is drawn from the
source's :class:`Distribution` *per unit tolerance*. The conventions follow what CETOL 6σ and 3DCS
users expect (``docs/statistical.md``):

Interval sources (dim 1, a length or angle error, ``|e| ≤ t``)::

  * ``uniform``:           z ~ U(-1, 1)                                   var = 1/3
  * ``normal``:            z ~ N(0, 1/k²): the tolerance is k standard deviations (t = k·σ,
                           k = ``sigma_k``, default 3), *not* truncated    var = 1/k²
  * ``truncated_normal``:  the same normal truncated at ±t                 var = (1 − 2kφ(k)/(2Φ(k)−1))/k²
  * ``mean_shift`` m (a fraction of t, process mean shift as in the "1.5σ shift" of six-sigma
    practice): every distribution above is moved by m·t, e.g. uniform on [(m−1)t, (m+1)t].

Disk / ball sources (dim 2 / 3, the radial clearance of a revolute / spherical joint, ``|e| ≤ t``):
the direction is uniform on the circle / sphere and the distribution names the *radius*::

  * ``uniform``: r ~ U(0, t) (Yao 2013 eq. 12, ``radial="uniform"``) or uniform over the
    disk/ball area/volume (``radial="area"``: r = t·U^(1/dim));
  * ``contact``: r = t exactly (the journal always touches its bearing, Lara-Molina 2019 Sec. 2.5);
  * ``normal``: every component ~ N(0, (t/k)²) (circular / spherical normal; the radius is
    Rayleigh / Maxwell distributed and may exceed t);
  * ``truncated_normal``: r = |N(0, (t/k)²)| truncated at t (the radius, not the components).

A mean shift has no natural direction on a disk or ball and is refused there.

Every distribution is isotropic, so its covariance per unit tolerance is ``variance · I_dim``
(:func:`unit_moments`); that is what the first-order ``yield`` measure uses
(:mod:`evotol.measures.statistical`). Samples are generated from uniforms by inverse CDFs
(:func:`draw`), so Latin hypercube stratification carries over to every distribution.

The parameters several definitions of this module share are described once, here.

Parameters
----------
dims : sequence of int
    Dimension of each source (1, 2 or 3).
n : int
    Number of samples.
"""
from __future__ import annotations

import functools

from dataclasses import dataclass

import numpy as np
from scipy import special, stats
from scipy.stats import qmc

from evotol.errors import ValidationError

KINDS = ("uniform", "normal", "truncated_normal", "contact")
RADIAL = ("uniform", "area")
METHODS = ("lhs", "mc")


@dataclass(frozen=True)
class Distribution:
    """How one source's error is distributed inside its tolerance t (see module docstring).

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.
    sigma_k : float
        k in t = k·σ for the normal kinds (> 0, default 3; 1, dimensionless).
    mean_shift : float
        Process mean shift as a fraction of t (interval sources only; ``|m| < 1``).

    Notes
    -----
    A plain value: :meth:`validate` raises :class:`evotol.errors.ValidationError`.

    Examples
    --------
    >>> from evotol import Distribution
    >>> normal = Distribution("normal", sigma_k=3.0)            # t = 3 sigma
    >>> normal.validate()
    >>> normal.is_normal, Distribution().kind
    (True, 'uniform')
    """

    kind: str = "uniform"
    sigma_k: float = 3.0
    mean_shift: float = 0.0

    def validate(self, field: str = "distribution", dim: int | None = None) -> None:
        """Check the settings; ``dim`` (1, 2, 3) also checks that they suit the source's shape.

        Parameters
        ----------
        field : str
            Name of the field in the error message.
        dim : {1, 2, 3} or None
            Dimension of the source's error vector, or None to check the settings alone.

        Raises
        ------
        evotol.errors.ValidationError
            An unknown ``kind``, ``sigma_k`` <= 0, ``|mean_shift|`` >= 1, a mean shift on a disk
            or ball source, or ``"contact"`` on an interval source.
        """
        if self.kind not in KINDS:
            raise ValidationError(f"{field}.kind", self.kind, f"one of {KINDS}")
        k = self.sigma_k
        if not isinstance(k, (int, float, np.floating)) or not np.isfinite(k) or k <= 0:
            raise ValidationError(f"{field}.sigma_k", k, "a positive number of standard deviations per tolerance (t = k·σ)")
        m = self.mean_shift
        if not isinstance(m, (int, float, np.floating)) or not np.isfinite(m) or abs(m) >= 1:
            raise ValidationError(f"{field}.mean_shift", m, "a process mean shift as a fraction of t, |m| < 1")
        if dim is None:
            return
        if dim > 1 and m != 0:
            raise ValidationError(f"{field}.mean_shift", m, f"0 for a {'disk' if dim == 2 else 'ball'} source "
                                  "(a mean shift has no direction there)")
        if dim == 1 and self.kind == "contact":
            raise ValidationError(f"{field}.kind", self.kind, "'contact' only for disk/ball clearances (dim 2 or 3)")

    @property
    def is_normal(self) -> bool:
        """True when the first-order error of this source is exactly normal (untruncated normal)."""
        return self.kind == "normal"


def as_distribution(value, field: str = "distribution", dim: int | None = None) -> Distribution:
    """A :class:`Distribution` from a Distribution, a kind name or a mapping (study files).

    Parameters
    ----------
    value : Distribution, str or dict
        A distribution, a kind name of :data:`KINDS`, or a mapping with keys among ``kind``,
        ``sigma_k``, ``mean_shift``.
    field : str
        Name of the field in error messages.
    dim : {1, 2, 3} or None
        Dimension of the source, to check that the distribution suits it; None checks the
        settings alone.

    Returns
    -------
    Distribution
        The validated distribution.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown mapping key, a value of another type, or settings that
        :meth:`Distribution.validate` refuses.
    """
    if isinstance(value, Distribution):
        d = value
    elif isinstance(value, str):
        d = Distribution(value)
    elif isinstance(value, dict):
        unknown = set(value) - {"kind", "sigma_k", "mean_shift"}
        if unknown:
            raise ValidationError(f"{field}.{sorted(unknown)[0]}", sorted(unknown)[0], "one of kind, sigma_k, mean_shift")
        d = Distribution(**value)
    else:
        raise ValidationError(field, value, f"a kind name {KINDS} or an evotol.measures.statistical.distributions.Distribution")
    d.validate(field, dim)
    return d


@functools.lru_cache(maxsize=1024)
def _checked(dist: Distribution, dim: int) -> Distribution:
    """``dist`` once validated for ``dim`` (a Monte Carlo draws per pose: checked once, not per pose and
    source); a refusal is raised every time (not cached)."""
    return as_distribution(dist, dim=dim)


def _truncated_variance(k: float) -> float:
    """Variance of N(0, 1) truncated at ±k."""
    return float(1 - 2 * k * stats.norm.pdf(k) / (2 * stats.norm.cdf(k) - 1))


def unit_moments(dist: Distribution, dim: int, radial: str = "uniform") -> tuple[float, float]:
    """(mean, variance per component) of z for unit tolerance; the covariance is variance·I_dim.

    The mean is non-zero only for an interval with a mean shift. Closed forms: uniform interval
    1/3; uniform radius r ~ U(0,1) on a disk/ball E[r²]/dim = 1/(3·dim); area-uniform
    E[r²] = dim/(dim+2); contact E[r²] = 1; normal 1/k²; truncated normal radius
    var_trunc(k)/(k²·dim) (interval: var_trunc(k)/k²).

    Parameters
    ----------
    dist : Distribution
        The source's distribution.
    dim : {1, 2, 3}
        Dimension of the source's error vector.
    radial : {"uniform", "area"}
        Radius law of a ``uniform`` disk/ball source (module docstring); ignored otherwise.

    Returns
    -------
    tuple of float
        ``(mean, variance)`` per component of z, per unit tolerance (dimensionless: multiply the
        mean by t and the variance by t² for SI units).
    """
    k = float(dist.sigma_k)
    if dist.kind == "normal":
        return dist.mean_shift, 1.0 / k ** 2
    if dist.kind == "truncated_normal":
        return dist.mean_shift, _truncated_variance(k) / k ** 2 / dim
    if dist.kind == "contact":
        return 0.0, 1.0 / dim
    if dim == 1:
        return dist.mean_shift, 1.0 / 3.0
    er2 = 1.0 / 3.0 if radial == "uniform" else dim / (dim + 2.0)
    return 0.0, er2 / dim


def uniforms(n: int, d: int, method: str = "lhs", seed=0) -> np.ndarray:
    """(n, d) uniforms in [0, 1): Latin hypercube (scipy.stats.qmc) or plain Monte Carlo.

    Parameters
    ----------
    d : int
        Number of columns (the sum of the source dimensions).
    method : {"lhs", "mc"}
        Latin hypercube or plain pseudo-random sampling.
    seed : int, numpy.random.Generator or None
        Seed of the generator (default 0: reproducible).

    Returns
    -------
    numpy.ndarray
        (n, d) uniforms in [0, 1).

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``method``.
    """
    if method not in METHODS:
        raise ValidationError("method", method, f"one of {METHODS}")
    if method == "lhs":
        return latin_hypercube(n, d, seed)
    return np.random.default_rng(seed).random((n, d))


def latin_hypercube(n: int, d: int, seed=0) -> np.ndarray:
    """(n, d) Latin hypercube in [0, 1): the draws of ``scipy.stats.qmc.LatinHypercube(d, seed=seed)
    .random(n)`` (scrambled, strength 1; SciPy 1.17's algorithm, draw for draw) without its set-up,
    which took 0.5 ms of the 0.9 ms a pose of a Monte Carlo verification (issue 43 item 4).

    Column k is ``(π_k(i) − u_ik) / n`` for a random permutation π_k of 1..n and uniforms u; a
    Generator ``seed`` is not drawn from: its first spawned child is (as SciPy does).
    ``tests/test_montecarlo_sampling.py`` compares it with SciPy's class.

    Parameters
    ----------
    d : int
        Number of columns.
    seed : int, numpy.random.Generator or None
        As :func:`uniforms`; anything else is passed to SciPy's class.

    Returns
    -------
    numpy.ndarray
        (n, d) stratified uniforms: each column has one value in each of the n strata.
    """
    if isinstance(seed, np.random.Generator):
        bg = seed.bit_generator
        rng = np.random.Generator(type(bg)(bg.seed_seq.spawn(1)[0]))
    elif seed is None or isinstance(seed, (int, np.integer)):
        rng = np.random.default_rng(seed)
    else:
        return qmc.LatinHypercube(d=d, seed=seed).random(n)
    return latin_hypercube_from(n, d, rng)


def latin_hypercube_from(n: int, d: int, rng: np.random.Generator) -> np.ndarray:
    """:func:`latin_hypercube` drawn from ``rng`` itself (the Generator SciPy's class would spawn).

    Parameters
    ----------
    d : int
        As :func:`latin_hypercube`.
    rng : numpy.random.Generator
        Drawn from: ``n d`` uniforms, then a permutation of 1..n per column.

    Returns
    -------
    numpy.ndarray
        (n, d) stratified uniforms.
    """
    u = rng.uniform(size=(n, d))
    perms = rng.permuted(np.tile(np.arange(1, n + 1), (d, 1)), axis=1)
    return (perms.T - u) / n


def _truncnorm_ppf(u: np.ndarray, a: float, b: float) -> np.ndarray:
    """Quantile of N(0, 1) truncated to [a, b] (same values as scipy.stats.truncnorm.ppf, faster)."""
    lo, hi = special.ndtr(a), special.ndtr(b)
    return np.clip(special.ndtri(lo + u * (hi - lo)), a, b)


def _radius(u: np.ndarray, dist: Distribution, dim: int, radial: str) -> np.ndarray:
    k = float(dist.sigma_k)
    if dist.kind == "contact":
        return np.ones_like(u)
    if dist.kind == "truncated_normal":
        return _truncnorm_ppf(u, 0.0, k) / k
    return u if radial == "uniform" else u ** (1.0 / dim)


def draw(U: np.ndarray, dims, dists, radial: str = "uniform") -> list[np.ndarray]:
    """Unit-tolerance errors per source from uniforms U (n, Σ dims): a list of (n, dim_j) arrays.

    dims: source dimensions (1, 2, 3); dists: :class:`Distribution` or kind names, one per source.
    Each source uses ``dim_j`` columns of U (interval: the value; disk: radius, angle; ball:
    radius, cos(polar angle), azimuth; a normal disk/ball: one column per component).

    Parameters
    ----------
    U : numpy.ndarray, (n, sum(dims))
        Uniforms in [0, 1), e.g. from :func:`uniforms`.
    dists : sequence of Distribution or str
        Distribution of each source (anything :func:`as_distribution` takes).
    radial : {"uniform", "area"}
        Radius law of ``uniform`` disk/ball sources (module docstring).

    Returns
    -------
    list of numpy.ndarray
        Per source, the (n, dim_j) errors per unit tolerance (dimensionless; multiply by t_j for
        m or rad).

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``radial``, or a distribution unfit for its source (:func:`as_distribution`).
    """
    if radial not in RADIAL:
        raise ValidationError("radial", radial, f"one of {RADIAL}")
    out, c = [], 0
    for dim, dist in zip(dims, dists):
        dist = _checked(dist, dim) if isinstance(dist, Distribution) else as_distribution(dist, dim=dim)
        k = float(dist.sigma_k)
        if dim == 1:
            u = U[:, c]
            if dist.kind == "uniform":
                z = 2 * u - 1
            elif dist.kind == "normal":
                z = special.ndtri(np.clip(u, 1e-300, 1 - 1e-16)) / k
            else:
                z = _truncnorm_ppf(u, -k, k) / k
            out.append((z + dist.mean_shift)[:, None])
            c += 1
            continue
        if dist.kind == "normal":          # circular / spherical normal: each component N(0, 1/k²)
            out.append(special.ndtri(np.clip(U[:, c:c + dim], 1e-300, 1 - 1e-16)) / k)
            c += dim
            continue
        r = _radius(U[:, c], dist, dim, radial)
        if dim == 2:
            a = 2 * np.pi * U[:, c + 1]
            d = np.stack([np.cos(a), np.sin(a)], 1)
        else:
            zc = 2 * U[:, c + 1] - 1
            a = 2 * np.pi * U[:, c + 2]
            s = np.sqrt(1 - zc ** 2)
            d = np.stack([s * np.cos(a), s * np.sin(a), zc], 1)
        out.append(r[:, None] * d)
        c += dim
    return out


def unit_samples(dims, dists, n: int, method: str = "lhs", seed=0, radial: str = "uniform") -> list[np.ndarray]:
    """One set of unit-tolerance samples (list over sources of (n, dim_j)), e.g. shared by all
    poses as common random numbers.

    Parameters
    ----------
    dists : sequence of Distribution or str
        Distribution of each source.
    method : {"lhs", "mc"}
        Latin hypercube or plain Monte Carlo (:func:`uniforms`).
    seed : int, numpy.random.Generator or None
        Seed of the uniforms (default 0).
    radial : {"uniform", "area"}
        Radius law of ``uniform`` disk/ball sources.

    Returns
    -------
    list of numpy.ndarray
        Per source, (n, dim_j) errors per unit tolerance (dimensionless).

    Raises
    ------
    evotol.errors.ValidationError
        As :func:`uniforms` and :func:`draw`.
    """
    return draw(uniforms(n, int(sum(dims)), method, seed), dims, dists, radial)
