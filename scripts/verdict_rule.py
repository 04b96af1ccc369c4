"""The verdict rule over training seeds and frames (issue 36; docs/experiment.md, "The verdict
rule over seeds and frames"), shared by scripts/experiment.py, which decides the claims with it,
and scripts/verdict_coverage.py, which measures its coverage.

    centre, lower, upper, df = combined_interval([d1, d2, d3], frame_variance, frame_df)

centre: the mean over the S seed pairs' paired differences A - B; variance: their sample variance
/ S (training) + `frame_variance` (the frames: the bootstrap variance, over resamples of the frames
drawn the same for every seed pair, of the seed-averaged difference); the interval reads a Student
t quantile at the Welch-Satterthwaite degrees of freedom of the two terms (`frame_df` the frame
term's: frames - 1, or resamples - 1 when it comes from a bootstrap).
"""

import math


def combined_interval(seed_differences, frame_variance, frame_df, confidence=0.95):
    """(centre, lower, upper, degrees of freedom); needs two seed pairs or more."""
    s = len(seed_differences)
    if s < 2:
        raise ValueError(f"combined_interval: {s} seed pair(s); the rule needs two or more")
    centre = sum(seed_differences) / s
    seed_var = sum((d - centre) ** 2 for d in seed_differences) / (s - 1) / s
    total = seed_var + frame_variance
    if total <= 0:
        return centre, centre, centre, math.inf
    denominator = seed_var ** 2 / (s - 1) + (frame_variance ** 2 / frame_df if frame_df > 0 else 0)
    df = total ** 2 / denominator if denominator > 0 else math.inf
    half = t_quantile(0.5 + confidence / 2, df) * math.sqrt(total)
    return centre, centre - half, centre + half, df


def t_quantile(p, df):
    """The Student t quantile (the normal one above 200 degrees of freedom), by bisection on the
    regularized incomplete beta function's continued fraction (no SciPy on the machines)."""
    if df > 200 or math.isinf(df):
        return _normal_quantile(p)

    def cdf(t):
        x = df / (df + t * t)
        ib = _betainc(df / 2, 0.5, x)
        return 1 - 0.5 * ib if t > 0 else 0.5 * ib

    lo, hi = -50.0, 50.0
    for _ in range(200):
        mid = (lo + hi) / 2
        if cdf(mid) < p:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def _normal_quantile(p):
    # Bisection on the normal CDF (erfc): slow, exact enough, no SciPy needed.
    lo, hi = -10.0, 10.0
    for _ in range(200):
        mid = (lo + hi) / 2
        if 0.5 * math.erfc(-mid / math.sqrt(2)) < p:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def _betainc(a, b, x):
    """The regularized incomplete beta function I_x(a, b) (Numerical Recipes' continued fraction)."""
    if x <= 0:
        return 0.0
    if x >= 1:
        return 1.0
    lbeta = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
    front = math.exp(lbeta + a * math.log(x) + b * math.log(1 - x))
    if x > (a + 1) / (a + b + 2):
        return 1 - _betainc(b, a, 1 - x)
    f, c, d = 1.0, 1.0, 0.0
    for i in range(400):
        m = i // 2
        if i == 0:
            num = 1.0
        elif i % 2 == 0:
            num = (m * (b - m) * x) / ((a + 2 * m - 1) * (a + 2 * m))
        else:
            num = -((a + m) * (a + b + m) * x) / ((a + 2 * m) * (a + 2 * m + 1))
        d = 1 + num * d
        d = 1 / (d if abs(d) > 1e-300 else 1e-300)
        c = 1 + num / (c if abs(c) > 1e-300 else 1e-300)
        f *= c * d
        if abs(1 - c * d) < 1e-12:
            break
    return front * (f - 1) / a
