"""Student's t distribution for the experiment's intervals (stats.py), without scipy: the
two-sided tail through the regularized incomplete beta function (its continued fraction,
evaluated by the modified Lentz method: Press et al., Numerical Recipes, 3rd ed., 6.4) and
the quantile by bisection."""

import functools
import math

_EPS = 1e-15
_TINY = 1e-300


def _beta_cf(a, b, x):
    """The continued fraction of the incomplete beta function I_x(a, b)."""
    c, d = 1.0, 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (d if abs(d) > _TINY else _TINY)
    h = d
    for m in range(1, 400):
        for num in (m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m)),
                    -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))):
            d = 1.0 + num * d
            d = 1.0 / (d if abs(d) > _TINY else _TINY)
            c = 1.0 + num / c
            c = c if abs(c) > _TINY else _TINY
            h *= d * c
        if abs(d * c - 1.0) < _EPS:
            break
    return h


def beta_inc(a, b, x):
    """The regularized incomplete beta function I_x(a, b), 0 <= x <= 1."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
                     + a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _beta_cf(a, b, x) / a
    return 1.0 - front * _beta_cf(b, a, 1.0 - x) / b


def two_sided_tail(t, df):
    """P(|T| > t) of Student's t with ``df`` (> 0, not necessarily whole) degrees of
    freedom."""
    t = abs(float(t))
    return beta_inc(df / 2.0, 0.5, df / (df + t * t))


@functools.lru_cache(maxsize=4096)
def quantile(level, df):
    """The t with P(|T| <= t) = ``level`` (0 < level < 1): the half-width factor of a
    two-sided ``level`` interval (``quantile(0.95, 3)`` = 3.182...)."""
    tail = 1.0 - float(level)
    lo, hi = 0.0, 1.0
    while two_sided_tail(hi, df) > tail:
        hi *= 2.0
        if hi > 1e12:
            return math.inf
    for _ in range(200):
        mid = (lo + hi) / 2.0
        if two_sided_tail(mid, df) > tail:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-12 * hi:
            break
    return (lo + hi) / 2.0
