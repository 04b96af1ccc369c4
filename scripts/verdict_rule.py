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
    df = welch_df(seed_var, s - 1, frame_variance, frame_df)
    half = t_quantile(0.5 + confidence / 2, df) * math.sqrt(total)
    return centre, centre - half, centre + half, df


def welch_df(seed_var, seed_df, frame_var, frame_df):
    """Welch-Satterthwaite's degrees of freedom of the sum of the two variance terms."""
    denominator = (seed_var ** 2 / seed_df if seed_df > 0 else 0) + \
        (frame_var ** 2 / frame_df if frame_df > 0 else 0)
    return (seed_var + frame_var) ** 2 / denominator if denominator > 0 else math.inf


# z at 80 % power: a claim is "decided with 80 % power" at (seeds, frames) where the true effect
# is at least (t(0.975, df) + POWER_Z) standard errors from 0.
POWER_Z = 0.8416212335729143


def decided_with_power(effect, seed_var, frames_var, seeds, frames, frame_df):
    """Whether a 95 % interval of the rule excludes 0 with 80 % power at `seeds` seed pairs and
    `frames` frames, if the true A - B is `effect`. seed_var: one seed pair's training variance
    (the sample variance of the seed pairs' differences; 0 for a claim on one training);
    frames_var(frames): the frame term's variance at that many frames (it scales as 1 / frames)."""
    a, b = seed_var / seeds, frames_var(frames)
    if a + b <= 0:
        return effect != 0
    df = welch_df(a, seeds - 1 if seed_var > 0 else 0, b, frame_df)
    return abs(effect) >= (t_quantile(0.975, df) + POWER_Z) * math.sqrt(a + b)


def power_needs(effect, seed_var, frame_var, frames, frame_df, seeds, max_seeds=100,
                max_frames_factor=1000):
    """(seed pairs needed at `frames` frames, frames needed at `seeds` seed pairs) to decide a
    claim whose true A - B is `effect` with 80 % power; None where more than max_seeds seed pairs,
    or more than max_frames_factor x `frames` frames, would not do it (the other term alone is
    too wide). frame_var: the frame term's variance measured at `frames` frames."""
    def frames_var(n):
        return frame_var * frames / n

    seeds_needed = None
    if seed_var > 0:
        seeds_needed = next((s for s in range(2, max_seeds + 1) if decided_with_power(
            effect, seed_var, frames_var, s, frames, frame_df)), None)
    frames_needed = None
    hi = frames * max_frames_factor
    if decided_with_power(effect, seed_var, frames_var, seeds, hi, frame_df):
        lo = 1
        while hi - lo > 1:  # decided at hi, not at lo (or lo = 1)
            mid = (lo + hi) // 2
            if decided_with_power(effect, seed_var, frames_var, seeds, mid, frame_df):
                hi = mid
            else:
                lo = mid
        frames_needed = hi
    return seeds_needed, frames_needed


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
