"""The truth's Monte Carlo noise and the delta-method variance of every comparison statistic.

One definition serves ``check`` (its intervals and verdicts), ``compare`` (its noise
floors and standard errors), ``study`` and ``sweep``.  The inputs, per pixel ``p`` of a
region and RGB channel ``c``:

* ``e[p, c]``: the error ``candidate - reference``;
* ``C[p]``: the ``3 x 3`` covariance of the noise of ``e[p]`` [units²]; the channels
  of a pixel share every path, so ``C`` is far from diagonal (correlation ~0.9 in fog;
  :meth:`fogref.gbuffer.Truth.noise_cov` reads it from the truth's ``stderr.*`` and
  ``corr.*`` channels).  Pixels are independent: each has its own samples;
* ``w[p, c]``: a weight (1, or relMSE's ``1 / (r² + eps)``).

Statistics and their variances (noise ``n ~ N(0, C)``, true error ``δ``):

* a weighted sum ``S = Σ w e``:  ``Var S = Σ_p w_pᵀ C_p w_p``;
* a debiased weighted square ``Q = Σ w (e² - C_cc)``, unbiased for ``Σ w δ²``:
  ``Var Q = Σ_p 4 (w δ)_pᵀ C_p (w δ)_p + 2 tr(W_p C_p W_p C_p) (1 + 1/(spp - 1))``,
  the last factor the noise of the estimated ``C_cc`` (its ``spp - 1`` degrees of
  freedom); ``δ`` is estimated by ``sign(e) sqrt(max(e² - C_cc, 0))``;
* a ratio ``S_e / S_r`` (``rel_bias``), with the reference's own noise ``R`` entering
  ``e`` with the opposite sign (``Cov(S_e, S_r) = -Var S_r``):
  ``Var ≈ (Var S_e + 2 ρ Var S_r + ρ² Var S_r) / S_r²``, ``ρ = S_e / S_r``.

Rounding: a deterministic part (``T`` of a pixel-exact truth) has no Monte Carlo
noise, but it is stored in float32 and a float32 model computes it with a few
rounding errors; :func:`rounding_var` is that floor, :data:`ROUNDING` ulp-scaled.

Examples
--------
Three perfectly correlated channels of standard error 1: the sum has variance 9,
not 3.

>>> import numpy as np
>>> C = np.ones((1, 3, 3))
>>> float(sum_var(C))
9.0
>>> float(sum_var(np.eye(3)[None]))
3.0
"""

from __future__ import annotations

import numpy as np

#: Relative rounding floor of a part [1]: float32 storage of the truth (half an ulp,
#: 2^-24) plus a float32 model's arithmetic, together 4 ulp of 2^-23.  Measured: Unreal's
#: exact extinction against a pixel-exact truth of the default scene differs by at most
#: 6 ulp (7.1e-7) and by 0.4 ulp in RMS.
ROUNDING = 4.0 * 2.0**-23


def rounding_var(reference, candidate) -> np.ndarray:
    """``(..., 3)`` variance [units²] of the rounding floor: ``(ROUNDING max(|r|, |x|))²``
    per channel (non-finite candidate values count as 0 here).

    >>> float(rounding_var(np.array([1.0]), np.array([0.5]))[0]) == ROUNDING**2
    True
    """
    r = np.abs(np.asarray(reference, dtype=np.float64))
    x = np.abs(np.asarray(candidate, dtype=np.float64))
    x = np.where(np.isfinite(x), x, 0.0)
    return (ROUNDING * np.maximum(r, x)) ** 2


def diagonal(C: np.ndarray) -> np.ndarray:
    """``(..., 3)`` the variances on the diagonal of covariances ``(..., 3, 3)``."""
    return np.diagonal(C, axis1=-2, axis2=-1)


def add_diagonal(C: np.ndarray, var: np.ndarray) -> np.ndarray:
    """``C`` with ``var (..., 3)`` added to its diagonal (independent noise per channel)."""
    out = np.array(C, dtype=np.float64, copy=True)
    for i in range(3):
        out[..., i, i] += var[..., i]
    return out


def scaled(C: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Covariance of ``a * n`` (channel-wise scale ``a (..., 3)``) for ``n`` of covariance ``C``."""
    a = np.asarray(a, dtype=np.float64)
    return C * a[..., :, None] * a[..., None, :]


def sqrt_psd(C: np.ndarray) -> np.ndarray:
    """A square root ``A`` of each covariance (``A Aᵀ = C``), negative eigenvalues (float32
    rounding of the stored correlations) clipped to 0: draws ``A z`` are noise like ``C``.

    >>> A = sqrt_psd(np.array([[4.0, 2.0], [2.0, 1.0]]))
    >>> np.allclose(A @ A.T, [[4.0, 2.0], [2.0, 1.0]])
    True
    """
    vals, vecs = np.linalg.eigh(np.asarray(C, dtype=np.float64))
    return vecs * np.sqrt(np.maximum(vals, 0.0))[..., None, :]


def sum_var(C: np.ndarray, w=None) -> float:
    """``Var Σ_p w_pᵀ n_p`` for noise of covariances ``C (N, 3, 3)`` and weights ``w (N, 3)``
    (default 1): ``Σ_p w_pᵀ C_p w_p`` [units²], >= 0."""
    if w is None:
        return max(float(C.sum()), 0.0)
    w = np.asarray(w, dtype=np.float64)
    return max(float(np.einsum("pi,pij,pj->", w, C, w)), 0.0)


def squared_stat(
    e: np.ndarray, C: np.ndarray, spp: int, w=None, at_spp: int | None = None
) -> tuple[float, float]:
    """The debiased weighted square ``Q = Σ w (e² - C_cc)`` and its variance.

    Parameters
    ----------
    e : ``(N, 3)`` errors [units].
    C : ``(N, 3, 3)`` noise covariance of ``e`` [units²].
    spp : samples per pixel of the truth behind ``C`` (0 or 1: ``C`` taken as exact).
    w : ``(N, 3)`` weights, default 1.
    at_spp : the variance ``Q`` would have from a truth of ``at_spp`` samples per pixel, its
        error pattern ``delta`` held (``C`` scaled by ``spp / at_spp``; needs ``spp`` >= 1).

    Returns
    -------
    ``(Q, Var Q)``: ``Q`` [w units²] may be < 0 by noise; ``Var Q`` >= 0.

    Examples
    --------
    A pixel off by exactly its noise in every channel, channels fully correlated:

    >>> Q, V = squared_stat(np.full((1, 3), 0.1), np.full((1, 3, 3), 0.01), spp=0)
    >>> round(Q, 12), round(V, 12)
    (0.0, 0.0018)
    """
    Q, lin, quad = _squared_terms(e, C, w)
    return Q, _variance(lin, quad, *_spp_factors(spp, at_spp))


def squared_stat_and_null(e: np.ndarray, C: np.ndarray, spp: int, w=None) -> tuple[float, float, float]:
    """:func:`squared_stat`'s ``(Q, Var Q)``, and the ``Var Q`` that a perfect model (``e = 0``)
    would have on the same noise.  Its quadratic term is the same and its linear term 0, so it
    costs nothing more; both variances are bitwise those of two :func:`squared_stat` calls.

    >>> e, C = np.full((2, 3), 0.1), np.full((2, 3, 3), 0.01)
    >>> squared_stat_and_null(e, C, 0)[1:] == (squared_stat(e, C, 0)[1], squared_stat(0 * e, C, 0)[1])
    True
    """
    Q, lin, quad = _squared_terms(e, C, w)
    factors = _spp_factors(spp, None)
    return Q, _variance(lin, quad, *factors), _variance(0.0, quad, *factors)  # e = 0: no linear term


def _squared_terms(e, C, w) -> tuple[float, float, float]:
    """``Q`` and the variance's linear (in the error pattern) and quadratic (noise only) terms."""
    e = np.asarray(e, dtype=np.float64)
    w = np.ones_like(e) if w is None else np.asarray(w, dtype=np.float64)
    v = diagonal(C)
    Q = float((w * (e * e - v)).sum())
    delta = np.sign(e) * np.sqrt(np.maximum(e * e - v, 0.0))
    wd = w * delta
    lin = 4.0 * np.einsum("pi,pij,pj->", wd, C, wd)
    WC = w[..., :, None] * C
    quad = 2.0 * np.einsum("pij,pji->", WC, WC)
    return Q, lin, quad


def _variance(lin, quad, k: float, extra: float) -> float:
    """``Var Q`` from its terms, the covariance scaled by ``k`` (:func:`_spp_factors`), >= 0."""
    return max(float(lin * k + quad * k * k * extra), 0.0)


def _spp_factors(spp: int, at_spp: int | None) -> tuple[float, float]:
    """The scale ``k`` of the covariance and the factor of the variance estimate's own noise."""
    k, n = (spp / at_spp, at_spp) if (at_spp and spp >= 1) else (1.0, spp)
    return k, 1.0 + (1.0 / (n - 1) if n > 1 else 0.0)


def ratio_var(num: float, den: float, var_num: float, var_den: float) -> float:
    """``Var(num / den)`` by the delta method when the denominator's noise enters the
    numerator with the opposite sign (``Cov = -var_den``, as the reference enters
    ``e = candidate - reference``).  NaN where ``den == 0``.

    >>> ratio_var(0.0, 2.0, 1.0, 0.0)
    0.25
    """
    if den == 0:
        return float("nan")
    rho = num / den
    return max(var_num + 2.0 * rho * var_den + rho * rho * var_den, 0.0) / (den * den)
