#!/usr/bin/env python3
"""How often does a verdict rule's 95 % interval cover the true difference? (issue 36)

A claim compares two models A and B, each trained with S seeds, on the same N validation frames.
What a safety case cares about is the expected difference mu between the two *recipes* (over
training seeds), not between two particular checkpoints. This simulation draws per-frame paired
differences

    d[s, f] = mu + u[s] + v[f] + e[s, f]

(u: the seed pair's training effect, sd sigma_seed; v: the frame's difficulty for the difference,
shared by every seed pair, sd sigma_frame; e: the rest, sd sigma_noise), so the seed pair s's
estimate is D[s] = mean_f d[s, f], and asks how often each rule's interval contains mu:

  frames-only  the rule of Table 1 today: seed pair 1's frame bootstrap (one training each),
               estimate D[1] +- 1.96 sd_frames(d[1, :]) / sqrt(N);
  two-stage    a two-stage bootstrap, seeds then frames: resample the S seed pairs with
               replacement, then the N frames (the same frame counts for every seed), statistic
               the mean over the drawn seed pairs of their frame-weighted means;
  seeds-t      a t interval over the S seed-level estimates D[s] (S - 1 degrees of freedom),
               which sees the seed variance but not the frames' shared part v;
  combined     mean_s D[s] with variance s^2(D) / S + var_frames(mean_s d[s, :]) / N, the second
               term the frame bootstrap's (here in closed form) of the seed-averaged difference,
               read with a t quantile at Welch-Satterthwaite's degrees of freedom: the rule
               "a paired test across seeds with the frame intervals inside".

The frame bootstrap is replaced by its normal approximation (the variance of a mean over frames)
in all but the two-stage rule, so that thousands of replications run in seconds; the two-stage
rule is bootstrapped for real (--boot resamples). Prints one line per scenario and rule:
coverage (the share of replications whose interval holds mu) and the mean interval width.

    /usr/bin/python3 scripts/verdict_coverage.py [--reps 2000] [--seeds 3] [--frames 1000]
"""

import argparse
import math

import numpy as np

from verdict_rule import _normal_quantile, combined_interval, t_quantile

# (name, sigma_seed, sigma_frame, sigma_noise): the effect's spread over training seeds, over
# frames shared by the seed pairs, and the rest, in units of the difference per frame (the seed
# pair's frame-mean then has sd about sqrt(2) / sqrt(N) = 0.045 from the frames with N = 1000).
# The third is the regime the SSD rows show (blurred RGB Car AP 0.026 / 0.141 / 0.345 over three
# seeds: seed variance dominates); the first has no seed variance at all.
SCENARIOS = [
    ("no seed variance", 0.0, 1.0, 1.0),
    ("seeds as large as frames", 0.05, 1.0, 1.0),
    ("seed variance dominates", 0.2, 1.0, 1.0),
    ("shared frame variance dominates", 0.0, 3.0, 1.0),
]


def simulate(rng, sigma_seed, sigma_frame, sigma_noise, seeds, frames, reps, boot):
    mu = 0.1
    z = _normal_quantile(0.975)
    t_seeds = t_quantile(0.975, seeds - 1)
    hits = {"frames-only": 0, "two-stage": 0, "seeds-t": 0, "combined": 0}
    widths = {k: 0.0 for k in hits}
    for _ in range(reps):
        u = rng.normal(0, sigma_seed, size=(seeds, 1))
        v = rng.normal(0, sigma_frame, size=(1, frames))
        e = rng.normal(0, sigma_noise, size=(seeds, frames))
        d = mu + u + v + e
        per_seed = d.mean(axis=1)

        # frames-only: seed pair 1 alone.
        half = z * d[0].std(ddof=1) / math.sqrt(frames)
        intervals = {"frames-only": (per_seed[0] - half, per_seed[0] + half)}

        # two-stage bootstrap: seeds with replacement, then frames (one frame count vector).
        stats = np.empty(boot)
        for b in range(boot):
            s_idx = rng.integers(0, seeds, size=seeds)
            f_w = rng.multinomial(frames, np.full(frames, 1 / frames))
            stats[b] = (d[s_idx] @ f_w).mean() / frames
        intervals["two-stage"] = tuple(np.quantile(stats, [0.025, 0.975]))

        # seeds-t.
        centre = per_seed.mean()
        seed_var = per_seed.var(ddof=1) / seeds
        half = t_seeds * math.sqrt(seed_var)
        intervals["seeds-t"] = (centre - half, centre + half)

        # combined (scripts/verdict_rule.py, as the experiment decides with it): the seed term +
        # the frame term of the seed-averaged difference, frames - 1 degrees of freedom.
        frame_var = d.mean(axis=0).var(ddof=1) / frames
        _, lo, hi, _ = combined_interval(list(per_seed), frame_var, frames - 1)
        intervals["combined"] = (lo, hi)

        for k, (lo, hi) in intervals.items():
            hits[k] += lo <= mu <= hi
            widths[k] += hi - lo
    return {k: (hits[k] / reps, widths[k] / reps) for k in hits}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reps", type=int, default=2000, help="replications per scenario")
    parser.add_argument("--seeds", type=int, default=3, help="training seeds per model")
    parser.add_argument("--frames", type=int, default=1000, help="validation frames")
    parser.add_argument("--boot", type=int, default=200, help="two-stage bootstrap resamples")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    print(f"{args.reps} replications, {args.seeds} seeds, {args.frames} frames; nominal 95 %")
    print("| scenario (sd seed / frame / noise) | rule | coverage | mean width |")
    print("|---|---|---|---|")
    for name, ss, sf, sn in SCENARIOS:
        result = simulate(rng, ss, sf, sn, args.seeds, args.frames, args.reps, args.boot)
        for rule, (coverage, width) in result.items():
            print(f"| {name} ({ss:g} / {sf:g} / {sn:g}) | {rule} | {100 * coverage:.1f} % | "
                  f"{width:.4f} |")


if __name__ == "__main__":
    main()
