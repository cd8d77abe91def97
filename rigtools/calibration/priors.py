r"""Prior distributions of the calibration parameters, vectorised for an ensemble sampler.

Four families, each optionally truncated to ``[lower, upper]`` (the density renormalised over
the interval):

=============  =========================  ===============================================
``dist``       parameters                 density on its support
=============  =========================  ===============================================
``uniform``    ``lower``, ``upper``       :math:`1 / (u - l)` on ``[l, u]``
``normal``     ``mu``, ``sd``             :math:`\phi((x - \mu)/\sigma) / \sigma`
``lognormal``  ``median``, ``sigma``      :math:`\phi(\ln(x / m) / \sigma) / (\sigma x)`, ``x > 0``
``halfnormal`` ``sd``                     :math:`2 \phi(x / \sigma) / \sigma`, ``x >= 0``
=============  =========================  ===============================================

``sigma`` of the log-normal is the standard deviation of ``ln x`` (so ``median = 1,
sigma = 0.3`` puts 95 % of the mass in ``[0.56, 1.80]``). Truncation bounds ``lower`` and
``upper`` are allowed on ``normal``, ``lognormal`` and ``halfnormal`` (inside their natural
support); ``truncated_normal`` is an alias of ``normal`` that requires both bounds.

Every prior evaluates ``logpdf`` on arrays (``-inf`` outside the support, never NaN for a
finite argument), maps uniform variates through ``ppf`` (for starting points and for
simulation-based calibration), and states its mean and standard deviation (for the
identifiability check of :mod:`rigtools.calibration.diagnostics`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Final, Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ndtr, ndtri

__all__ = [
    "DISTRIBUTIONS",
    "Distribution",
    "Prior",
    "prior_from_mapping",
]

Distribution = Literal["uniform", "normal", "lognormal", "halfnormal"]
#: Accepted ``dist`` names and the keys each takes (required, optional).
DISTRIBUTIONS: Final[dict[str, tuple[tuple[str, ...], tuple[str, ...]]]] = {
    "uniform": (("lower", "upper"), ()),
    "normal": (("mu", "sd"), ("lower", "upper")),
    "truncated_normal": (("mu", "sd", "lower", "upper"), ()),
    "lognormal": (("median", "sigma"), ("lower", "upper")),
    "halfnormal": (("sd",), ("upper",)),
}
_LOG_SQRT_2PI: Final = 0.5 * math.log(2.0 * math.pi)
#: Points of the midpoint rule in probability space for the moments of a prior.
_MOMENT_POINTS: Final = 20001


@dataclass(frozen=True)
class Prior:
    """A univariate prior, possibly truncated to ``[lower, upper]``.

    Parameters
    ----------
    dist : {"uniform", "normal", "lognormal", "halfnormal"}
    loc : float
        ``mu`` (normal), ``ln(median)`` (lognormal); 0 otherwise.
    scale : float
        ``sd`` (normal, halfnormal), ``sigma`` (lognormal, of ``ln x``); ``upper - lower``
        (uniform).
    lower, upper : float
        Support, after truncation (``-inf``/``inf`` where open).

    Examples
    --------
    >>> p = Prior("uniform", 0.0, 100.0, 0.0, 100.0)
    >>> float(p.logpdf(50.0)) == -math.log(100.0), float(p.logpdf(-1.0))
    (True, -inf)
    >>> round(float(p.ppf(0.25)), 12)
    25.0
    """

    dist: Distribution
    loc: float
    scale: float
    lower: float
    upper: float

    # -- the untruncated family, in standardised form ---------------------------------------
    def _z(self, x: np.ndarray) -> np.ndarray:
        if self.dist == "lognormal":
            with np.errstate(divide="ignore", invalid="ignore"):
                return (np.log(x) - self.loc) / self.scale
        return (x - self.loc) / self.scale

    def _base_cdf(self, x: float) -> float:
        if self.dist == "uniform":
            return min(max((x - self.lower) / self.scale, 0.0), 1.0)
        if self.dist == "halfnormal":
            return 0.0 if x <= 0 else float(2.0 * ndtr(x / self.scale) - 1.0)
        if self.dist == "lognormal" and x <= 0:
            return 0.0
        if math.isinf(x):
            return 0.0 if x < 0 else 1.0
        return float(ndtr(self._z(np.asarray(x, dtype=float))))

    @property
    def _mass(self) -> tuple[float, float]:
        lo, hi = self._base_cdf(self.lower), self._base_cdf(self.upper)
        return lo, hi

    @property
    def log_normaliser(self) -> float:
        """``ln`` of the untruncated probability of ``[lower, upper]`` (0 when untruncated)."""
        if self.dist == "uniform":
            return 0.0
        lo, hi = self._mass
        return math.log(hi - lo)

    # -- public API ---------------------------------------------------------------------------
    @property
    def support(self) -> tuple[float, float]:
        """``(lower, upper)``: where the density is positive."""
        return self.lower, self.upper

    def contains(self, value: float) -> bool:
        """True if ``value`` lies in the support."""
        return bool(self.lower <= value <= self.upper) and math.isfinite(value)

    def logpdf(self, x: ArrayLike) -> np.ndarray:
        """Log density at ``x`` (``-inf`` outside the support).

        Parameters
        ----------
        x : array_like
            Values in the parameter's unit.

        Returns
        -------
        numpy.ndarray
            Same shape as ``x``.
        """
        v = np.asarray(x, dtype=float)
        inside = (v >= self.lower) & (v <= self.upper)
        const = self.log_density_constant
        if self.dist == "uniform":
            return np.where(inside, const, -np.inf)
        with np.errstate(over="ignore", invalid="ignore"):
            if self.dist == "lognormal":
                lv = np.log(np.maximum(v, 1e-300))
                z = (lv - self.loc) / self.scale
                out = const - 0.5 * z * z - lv
            else:
                z = (v - self.loc) / self.scale
                out = const - 0.5 * z * z
        return np.where(inside, out, -np.inf)

    @functools.cached_property
    def log_density_constant(self) -> float:
        """The log density's constant part (normalisation, truncation, half-normal's 2)."""
        if self.dist == "uniform":
            return -math.log(self.scale)
        c = -_LOG_SQRT_2PI - math.log(self.scale) - self.log_normaliser
        return c + math.log(2.0) if self.dist == "halfnormal" else c

    def ppf(self, u: ArrayLike) -> np.ndarray:
        """Quantile function: the value below which a fraction ``u`` of the mass lies.

        Parameters
        ----------
        u : array_like
            Probabilities in ``[0, 1]``.

        Returns
        -------
        numpy.ndarray
        """
        p = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        if self.dist == "uniform":
            return self.lower + p * self.scale
        lo, hi = self._mass
        q = lo + p * (hi - lo)
        if self.dist == "halfnormal":
            out = self.scale * ndtri(np.clip(0.5 * (q + 1.0), 0.5, 1.0))
        else:
            z = ndtri(q)
            out = self.loc + self.scale * z
            if self.dist == "lognormal":
                out = np.exp(out)
        return np.clip(out, self.lower, self.upper)

    def sample(self, rng: np.random.Generator, size: int | tuple[int, ...]) -> np.ndarray:
        """Independent draws (inverse-transform sampling with ``rng``)."""
        return self.ppf(rng.random(size))

    def moments(self) -> tuple[float, float]:
        """Mean and standard deviation (by the midpoint rule in probability space)."""
        u = (np.arange(_MOMENT_POINTS) + 0.5) / _MOMENT_POINTS
        x = self.ppf(u)
        return float(np.mean(x)), float(np.std(x))

    def describe(self) -> str:
        """Short text, e.g. ``uniform(0, 100)`` or ``lognormal(median=1, sigma=0.3)``."""
        if self.dist == "uniform":
            return f"uniform({self.lower:g}, {self.upper:g})"
        if self.dist == "normal":
            body = f"normal(mu={self.loc:g}, sd={self.scale:g})"
        elif self.dist == "lognormal":
            body = f"lognormal(median={math.exp(self.loc):g}, sigma={self.scale:g})"
        else:
            body = f"halfnormal(sd={self.scale:g})"
        natural = {"normal": (-math.inf, math.inf), "lognormal": (0.0, math.inf),
                   "halfnormal": (0.0, math.inf)}[self.dist]
        if (self.lower, self.upper) != natural:
            body += f" truncated to [{self.lower:g}, {self.upper:g}]"
        return body

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the keys of the TOML table that makes it)."""
        d: dict[str, Any] = {"dist": self.dist}
        if self.dist == "uniform":
            return {**d, "lower": self.lower, "upper": self.upper}
        if self.dist == "normal":
            d.update(mu=self.loc, sd=self.scale)
        elif self.dist == "lognormal":
            d.update(median=math.exp(self.loc), sigma=self.scale)
        else:
            d.update(sd=self.scale)
        if math.isfinite(self.lower) and not (self.dist != "normal" and self.lower == 0.0):
            d["lower"] = self.lower
        if math.isfinite(self.upper):
            d["upper"] = self.upper
        return d


def prior_from_mapping(spec: dict[str, Any]) -> Prior:
    """Build a :class:`Prior` from a validated mapping (``dist`` plus its keys).

    Values are taken as given; :func:`rigtools.calibration.config.parse_calibration_block`
    checks keys, numbers and ordering first and names the TOML line. This function raises
    ``ValueError`` with the key for anything it cannot build.

    Parameters
    ----------
    spec : dict
        ``{"dist": "uniform", "lower": 0, "upper": 100}`` and the like (module table).

    Returns
    -------
    Prior

    Examples
    --------
    >>> prior_from_mapping({"dist": "lognormal", "median": 1.0, "sigma": 0.3}).describe()
    'lognormal(median=1, sigma=0.3)'
    """
    dist = spec["dist"]
    if dist not in DISTRIBUTIONS:
        raise ValueError(f"`dist` must be one of {', '.join(DISTRIBUTIONS)}, was {dist!r}")
    lo = float(spec.get("lower", -math.inf))
    hi = float(spec.get("upper", math.inf))
    if dist == "uniform":
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"`lower` < `upper` (finite) required, were {lo!r}, {hi!r}")
        return Prior("uniform", 0.0, hi - lo, lo, hi)
    if dist in ("normal", "truncated_normal"):
        sd = float(spec["sd"])
        if not sd > 0:
            raise ValueError(f"`sd` must be > 0, was {sd!r}")
        if not lo < hi:
            raise ValueError(f"`lower` < `upper` required, were {lo!r}, {hi!r}")
        return Prior("normal", float(spec["mu"]), sd, lo, hi)
    if dist == "lognormal":
        median, sigma = float(spec["median"]), float(spec["sigma"])
        if not median > 0:
            raise ValueError(f"`median` must be > 0, was {median!r}")
        if not sigma > 0:
            raise ValueError(f"`sigma` must be > 0, was {sigma!r}")
        lo = max(lo, 0.0)
        if not lo < hi:
            raise ValueError(f"`lower` < `upper` required, were {lo!r}, {hi!r}")
        return Prior("lognormal", math.log(median), sigma, lo, hi)
    sd = float(spec["sd"])
    if not sd > 0:
        raise ValueError(f"`sd` must be > 0, was {sd!r}")
    if not hi > 0:
        raise ValueError(f"`upper` must be > 0, was {hi!r}")
    return Prior("halfnormal", 0.0, sd, 0.0, hi)
