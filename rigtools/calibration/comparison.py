r"""Which reading of the model the data support: PSIS-LOO over the model variants.

(The same comparison ranks the SDOF models of the run-up calibration, issue 20: there an
observation is one point of one channel's Arms curve, the variable ``arms``.)

Each variant (``secant_path``, ``secant_mesh``, ``tangent``) is fitted with the same priors,
stiffness scale and error terms; its pointwise log-likelihood is the per-run mixture
likelihood (a run, with all its candidate peaks, is one observation). Pareto-smoothed
importance-sampling leave-one-out cross-validation (Vehtari, Gelman and Gabry 2017, through
:func:`arviz.loo` and :func:`arviz.compare`) estimates each variant's expected log predictive
density ``elpd_loo`` for a new run, with its standard error; ``compare`` gives the difference
to the best and the standard error of that difference ``dse``.

Decision rule, stated: the best-ranked variant is **favoured** when its lead over the runner-up
exceeds both 4 (differences below about 4 in elpd are small, Sivula et al. 2022) and twice
``dse``; otherwise the data cannot tell the variants apart, ``favoured`` is None and the
statement says so. The largest Pareto ``k`` of each variant is reported: above 0.7 the
importance sampling for that run is unreliable (the run is very influential, often a run
near the jam or at the lowest torque) and the statement names the variant and how many of its
observations (runs, or a run-up's windows) are affected. A run whose
log-likelihood is the same for every draw (its peaks are all background under every draw)
has equal importance weights, so PSIS is exact there; arviz's tail fit returns ``inf`` for
it, which is not reported as a bad ``k``.

References
----------
.. [1] A. Vehtari, A. Gelman, J. Gabry, "Practical Bayesian model evaluation using
   leave-one-out cross-validation and WAIC", Statistics and Computing 27 (2017) 1413-1432.
.. [2] T. Sivula, M. Magnusson, A. A. Matamoros, A. Vehtari, "Uncertainty in Bayesian
   leave-one-out cross-validation based model comparison", arXiv:2008.10296 (2022).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Final

import arviz as az
import numpy as np

__all__ = ["ELPD_SMALL", "PARETO_K_BAD", "ModelComparison", "compare_variants"]

#: Differences in elpd below this are small (Sivula et al.).
ELPD_SMALL: Final = 4.0
#: Pareto k above this makes the PSIS estimate for that observation unreliable.
PARETO_K_BAD: Final = 0.7


@dataclass(frozen=True)
class ModelComparison:
    """PSIS-LOO comparison of the fitted variants.

    Attributes
    ----------
    criterion : str
        ``"psis-loo"``.
    variants : dict
        Name -> ``elpd_loo``, ``se``, ``p_loo``, ``pareto_k_max``, ``n_pareto_k_bad``,
        ``elpd_diff``, ``dse``, ``weight``, ``rank``.
    favoured : str or None
        None when the data cannot tell the best variants apart.
    statement : str
        The decision in words, with the numbers.
    """

    criterion: str
    variants: dict[str, dict[str, Any]]
    favoured: str | None
    statement: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {"criterion": self.criterion, "variants": self.variants,
                "favoured": self.favoured, "statement": self.statement}


def _f(x: Any) -> float | None:
    v = float(x)
    return v if math.isfinite(v) else None


def _log_likelihood_variable(idata: az.InferenceData) -> Any:
    """The one variable of the ``log_likelihood`` group."""
    group = idata["log_likelihood"]
    names = list(group.data_vars)
    if len(names) != 1:
        raise ValueError(f"the log_likelihood group must hold one variable, held {names}")
    return group[names[0]]


def compare_variants(idata: Mapping[str, az.InferenceData]) -> ModelComparison:
    """Compare variants by PSIS-LOO (module notes).

    Parameters
    ----------
    idata : mapping
        Variant name -> InferenceData with a ``log_likelihood`` group holding one variable
        (dims ``chain, draw`` and one observation dimension): ``f_n`` over ``run`` for the
        natural-frequency variants, ``arms`` over ``obs`` for the run-up models
        (:mod:`rigtools.calibration.runup_api`); every variant must use the same name.

    Returns
    -------
    ModelComparison
    """
    with warnings.catch_warnings():
        # arviz warns when some Pareto k is high; the numbers are reported below instead
        warnings.simplefilter("ignore")
        loos = {name: az.loo(d, pointwise=True) for name, d in idata.items()}
        table = az.compare(dict(idata), ic="loo") if len(idata) > 1 else None
    variants: dict[str, dict[str, Any]] = {}
    sizes: dict[str, int] = {}
    for name, loo in loos.items():
        k = np.asarray(loo.pareto_k, dtype=float)
        sizes[name] = int(k.size)
        ll = np.asarray(_log_likelihood_variable(idata[name]))
        constant = np.ptp(ll.reshape(-1, ll.shape[-1]), axis=0) < 1e-9
        k = np.where(constant, -np.inf, k)     # equal weights: PSIS is exact there
        row: dict[str, Any] = {
            "elpd_loo": _f(loo.elpd_loo), "se": _f(loo.se), "p_loo": _f(loo.p_loo),
            "pareto_k_max": _f(np.max(k)) if np.isfinite(np.max(k)) else None,
            "n_pareto_k_bad": int(np.sum(k > PARETO_K_BAD)),
        }
        if table is not None:
            t = table.loc[name]
            row.update(elpd_diff=_f(t["elpd_diff"]), dse=_f(t["dse"]), weight=_f(t["weight"]),
                       rank=int(t["rank"]))
        else:
            row.update(elpd_diff=0.0, dse=0.0, weight=1.0, rank=0)
        variants[name] = row
    ranked = sorted(variants, key=lambda n: variants[n]["rank"])
    bad = [n for n in ranked if variants[n]["n_pareto_k_bad"]]
    counts = ", ".join(f"{n} ({variants[n]['n_pareto_k_bad']} of {sizes[n]})"
                       for n in bad)
    caveat = (f" Pareto k above {PARETO_K_BAD:g} for {counts} observations (influential ones: "
              "runs, or windows of a run-up; the elpd of those variants is less certain than "
              "its se says)." if bad else "")
    if len(ranked) < 2:
        return ModelComparison("psis-loo", variants, ranked[0] if ranked else None,
                               "only one variant fitted; nothing to compare." + caveat)
    best, second = ranked[0], ranked[1]
    diff = variants[second]["elpd_diff"] or 0.0
    dse = variants[second]["dse"] or 0.0
    if diff > ELPD_SMALL and diff > 2.0 * dse:
        statement = (f"the data favour {best}: elpd_loo {variants[best]['elpd_loo']:.1f} "
                     f"(se {variants[best]['se']:.1f}), ahead of {second} by {diff:.1f} "
                     f"(dse {dse:.1f}; more than {ELPD_SMALL:g} and 2 dse).")
        favoured: str | None = best
    else:
        statement = (f"the data cannot tell {best} and {second} apart: elpd_loo difference "
                     f"{diff:.1f} with dse {dse:.1f} (a preference needs more than "
                     f"{ELPD_SMALL:g} and 2 dse).")
        favoured = None
    return ModelComparison("psis-loo", variants, favoured, statement + caveat)
