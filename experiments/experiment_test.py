#!/usr/bin/env python3
"""ctest experiment.miniature: scripts/experiment.py end to end on experiments/miniature.json (4
synthetic frames with LiDAR, 2 of them val: the committed SSDs, RPN models trained for one step
with 2 seeds each, 3D models for one step, a model without a checkpoint), then:

- every number of the generated table1.md equals the one in its results.json / bootstrap.csv
  (read here independently of the generator), the paper's column equals paper_figures.csv, and the
  absent model's rows and pair are 'missing' rows;
- the training-variance rows are the mean and standard deviation over the seeds' results.json;
- each claim of miniature_claims.csv gets the verdict its bootstrap.csv interval gives (one of
  each: confirmed, refuted, inconclusive, not measured for a missing model and for a non-pair;
  the Brier-terms flip claims from both terms' intervals, the sweep claim from sweep.csv);
- the compression overlay holds both SSDs sharp and blurred;
- a "kitti" source (the miniature's synthetic set read as a KITTI root) gives the synth run's rows,
  and a root without training/ or ImageSets/val.txt is refused naming the field;
- on a local Dask cluster of 2 workers the same steps give the same table, weights, detections
  and bootstrap tables byte for byte and the same results.json results, and a run without Dask
  finds them complete; a step failing on Dask stops the run with its error, keeping the markers
  of what ran;
- a second run runs nothing and changes nothing; a detection whose marker is gone runs again with
  exactly the steps downstream of it (its evaluations and compares);
- a checkpoint replaced under the same path reruns its detections and their evaluations;
- --update-docs replaces only the marked section of a copy of docs/RESULTS.md;
- a config error, and a claim of an unknown kind, names the file and the field;
- committed checkpoints per training seed ("seed_model") expand into one model per seed;
- calibration on a held-out split: the split's halves, each calibration file fitted on the first
  half at the model's Table 1 overlap kind, every row of the table against the held-out
  evaluations' results.json, the same rows from a "kitti" source, and the calibration steps rerun
  with their detection.

Usage: experiment_test.py REPO_ROOT BIN_DIR WORK_DIR
"""

import csv
import importlib.util
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

repo, bin_dir, work = (pathlib.Path(a).resolve() for a in sys.argv[1:4])
script = repo / "scripts" / "experiment.py"
sys.path.insert(0, str(repo / "scripts"))
import verdict_rule  # noqa: E402  (the rule over seeds the verdicts are checked against)

# The rule by hand: seed differences 1 and 3, no frame variance: centre 2, variance var(1, 3) / 2 =
# 1, 1 degree of freedom, t(0.975, 1) = 12.7062 (tables); with frame variance 1 and 99 frame
# degrees of freedom, variance 2 and df = 4 / (1 + 1 / 99) = 3.96.
_c, _lo, _hi, _df = verdict_rule.combined_interval([1.0, 3.0], 0.0, 99)
assert _c == 2.0 and abs(_lo - (2 - 12.7062)) < 1e-3 and abs(_hi - (2 + 12.7062)) < 1e-3 and _df == 1
_c, _lo, _hi, _df = verdict_rule.combined_interval([1.0, 3.0], 1.0, 99)
assert abs(_df - 4 / (1 + 1 / 99)) < 1e-12 and _lo < 2 - 2.77 * 2 ** 0.5 < _lo + 0.1
config_path = repo / "experiments" / "miniature.json"
out = work / "out"
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print(f"FAIL: {message}")


def run(*extra, expect=0):
    p = subprocess.run([sys.executable, str(script), "--config", str(config_path), "--out",
                        str(out), "--bin", str(bin_dir), *extra], capture_output=True, text=True)
    if p.returncode != expect:
        print(p.stdout, p.stderr)
        raise SystemExit(f"experiment.py exited {p.returncode}, expected {expect}")
    return p


METRIC = {"ssd": "2d", "rpn": "2d", "det3d": "3d"}


def cells(results_json, cls, metric="2d"):
    with open(results_json) as f:
        for r in json.load(f)["results"]:
            if r["class"] == cls and r["difficulty"] == "Moderate" and r["metric"] == metric:
                return r
    return None


def with_interval(cell, key, value, scale):
    b = cell["bootstrap"][key]
    text = f"{value * scale:.3f}" if value is not None else "n/a"
    if b["lower"] is not None and b["upper"] is not None:
        text += f" [{b['lower'] * scale:.3f}, {b['upper'] * scale:.3f}]"
    return text


def parse_tables(text):
    """{(class, 'table'|'pairs'): [row cells]} from the generated Markdown."""
    tables, cls, kind = {}, None, None
    for line in text.splitlines():
        m = re.match(r"### Table 1, (\w+)", line)
        if m:
            cls, kind = m.group(1), "table"
        elif line.startswith("Paired differences"):
            kind = "pairs"
        elif line.startswith("Brier scores by their terms"):
            kind = "brier"
        elif line.startswith("Training variance"):
            kind = "variance"
        elif line.startswith("### Verdicts"):
            cls, kind = "all", "verdicts"
        elif line.startswith("### What deciding"):
            cls, kind = "all", "power"
        elif line.startswith("### Percentile against BCa"):
            cls, kind = "all", "bca"
        elif line.startswith("Filter sweep"):
            cls, kind = "all", "sweep"
        elif line.startswith("### Calibration on a held-out split"):
            cls, kind = "all", "calibration"
        elif line.startswith("| ") and cls and not line.startswith("| model |") \
                and not line.startswith("| A - B |") and not line.startswith("| claim |"):
            tables.setdefault((cls, kind), []).append([c.strip() for c in line.strip("|").split("|")])
    return tables


shutil.rmtree(work, ignore_errors=True)
work.mkdir(parents=True)
config = json.loads(config_path.read_text())
# The models and pairs as the pipeline expands them: one per training seed (NAME-seedS).
models, groups = [], {}
for model in config["models"]:
    seeds = model.get("seeds", [])
    groups[model["name"]] = [f"{model['name']}-seed{x}" for x in seeds] or [model["name"]]
    models += [dict(model, name=n, group=model["name"]) for n in groups[model["name"]]]
config["models"] = models
config["pairs"] = [[x, y] for a, b in config["pairs"] for x, y in zip(groups[a], groups[b])]
first = run()
m = re.search(r"experiment: (\d+) steps run, (\d+) skipped, ([0-9.]+) s", first.stdout)
check(m is not None, "first run prints its summary")
steps = int(m.group(1)) if m else 0
# synth, stereo points (val only: the 3D models are the committed ones, not trained here), 4
# trainings (2 x 2 RPN seeds), detect: 6 image models x 2 blurs + 2 3D models, 2 evals each,
# compares: 3 image pairs (the SSDs, 2 RPN seed pairs) x 2 blurs x 2 matchers + the 3D pair x 2
# matchers, figures: the models' report, the blur report, the 3D pair's compare report and the
# filter sweep, the compression overlay = 1 + 1 + 4 + 14 + 28 + 14 + 5 = 67; the BCa check of the
# claims' compares: ssd-rgb vs ssd-rgbh-fixed sharp optimal, blurred kitti and blurred optimal, the
# 2 RPN seed pairs sharp optimal = 5. Calibration on a held-out split, for the 4 models of
# calibration.models: 3 fits and 4 evaluations of the held-out half each = 28. The replication
# set: its data, stereo points, the 14 detections, 28 evaluations, 14 compares, 5 BCa checks and
# the sweep = 64. 67 + 5 + 28 + 64 = 164.
check(steps == 164 and m.group(2) == "0", f"first run: 164 steps, none skipped (got {m.groups()})")
table_text = (out / "table1.md").read_text()
tables = parse_tables(table_text)

paper = {}
with open(repo / "experiments" / "paper_figures.csv") as f:
    for r in csv.DictReader(line for line in f if not line.startswith("#")):
        paper[(r["model"], r["blur_sigma_px"], r["class"], r["measure"])] = float(r["value"])

checked = 0
for cls in config["classes"]:
    rows = {(r[0], r[1]): r for r in tables.get((cls, "table"), [])}
    for model in config["models"]:
        blurs = ["0"] if model["family"] == "det3d" else ["0", "5"]
        for blur in blurs:
            row = rows.get((model["name"], blur))
            check(row is not None, f"{cls}: a row for {model['name']} blur {blur}")
            if row is None:
                continue
            for col, measure in ((8, "ap"), (9, "brier_labels")):
                want = paper.get((model["group"], blur, cls, measure))
                check(row[col] == (f"{want:.3f}" if want is not None else "n/a"),
                      f"{cls} {model['name']} blur {blur}: paper {measure} {row[col]!r}")
            if "train" not in model and not (repo / model["model"] / "model.pt").exists():
                check(row[3].startswith("missing: no checkpoint"),
                      f"{cls} {model['name']}: a missing row, got {row[3]!r}")
                continue
            run_dir = out / "runs" / model["name"] / f"blur{blur}"
            metric = METRIC[model["family"]]
            check(row[2] == metric, f"{cls} {model['name']}: overlap {row[2]!r}")
            k = cells(run_dir / "eval-kitti" / "results.json", cls, metric)
            o = cells(run_dir / "eval-optimal" / "results.json", cls, metric)
            if not k.get("evaluated", True):
                check(row[3] == "not evaluated (no detection of the class)",
                      f"{cls} {model['name']}: a not-evaluated row, got {row[3]!r}")
                checked += 1
                continue
            want = [str(k["num_valid_labels"]), with_interval(k, "ap_r40", k["ap_r40"], 0.01),
                    with_interval(k, "ap_r11", k["ap_r11"], 0.01),
                    with_interval(o, "ap_r40", o["ap_r40"], 0.01),
                    with_interval(o, "brier_labels", o["brier"]["over_labels"], 1.0)]
            check(row[3:8] == want, f"{cls} {model['name']} blur {blur}: {row[3:8]} != {want}")
            brier = {(r[0], r[1]): r for r in tables.get((cls, "brier"), [])}.get(
                (model["name"], blur))
            b = o["brier"]
            want = [with_interval(o, "brier_labels", b["over_labels"], 1.0),
                    with_interval(o, "brier_detections", b["over_detections"], 1.0),
                    with_interval(o, "brier_all", b["over_all"], 1.0)]
            check(brier is not None and brier[2:5] == want,
                  f"{cls} {model['name']} blur {blur}: Brier terms {brier} != {want}")
            checked += 1
    pairs = {(r[0], r[1], r[2]): r for r in tables.get((cls, "pairs"), [])}
    by_name = {m["name"]: m for m in config["models"]}
    for a_name, b_name in [p for p in config["pairs"] if "ssd-absent" not in p]:
        family = by_name[a_name]["family"]
        metric = METRIC[family]
        for blur, matcher in [(b, mt) for b in (["0"] if family == "det3d" else ["0", "5"])
                              for mt in ("kitti", "optimal")]:
            row = pairs.get((f"{a_name} - {b_name}", blur, matcher))
            check(row is not None, f"{cls}: a paired row {a_name} - {b_name}, blur {blur}, {matcher}")
            if row is None:
                continue
            path = out / "compare" / f"{a_name}-vs-{b_name}" / f"blur{blur}" / matcher
            with open(path / "bootstrap.csv") as f:
                got = {r["measure"]: r for r in csv.DictReader(f) if r["class"] == cls
                       and r["metric"] == metric and r["difficulty"] == "Moderate"}
            for col, measure, scale in ((3, "ap_r40", 0.01), (4, "brier_labels", 1.0)):
                r = got.get(measure)
                if r is None or r["a_minus_b"] == "":
                    check(row[col] == "n/a", f"{cls} pair {measure}: n/a, got {row[col]!r}")
                    continue
                d, lo, hi = (float(r[c]) * scale for c in
                             ("a_minus_b", "a_minus_b_lower", "a_minus_b_upper"))
                want = f"{d:+.3f} [{lo:+.3f}, {hi:+.3f}]" + (" *" if lo > 0 or hi < 0 else "")
                check(row[col] == want, f"{cls} pair blur {blur} {matcher} {measure}: "
                      f"{row[col]!r} != {want!r}")
                # The paired difference of the estimates is the difference of the two tables'.
                a = cells(out / "runs" / a_name / f"blur{blur}" / f"eval-{matcher}" /
                          "results.json", cls, metric)
                b = cells(out / "runs" / b_name / f"blur{blur}" / f"eval-{matcher}" /
                          "results.json", cls, metric)
                va = a["ap_r40"] if measure == "ap_r40" else a["brier"]["over_labels"]
                vb = b["ap_r40"] if measure == "ap_r40" else b["brier"]["over_labels"]
                check(abs(float(r["a_minus_b"]) - (va - vb)) < 1e-9,
                      f"{cls} pair {measure}: bootstrap.csv's A - B is the results' difference")
            checked += 1
    missing_pair = pairs.get(("ssd-rgb - ssd-absent", "", ""))
    check(missing_pair is not None and missing_pair[3] == "missing: ssd-absent",
          f"{cls}: the pair with the absent model is a missing row")
    # Training variance over the RPN seeds.
    variance = {(r[0], r[1]): r for r in tables.get((cls, "variance"), [])}
    for group in ("rpn-rgb", "rpn-rgbd"):
        for blur in ("0", "5"):
            row = variance.get((group, blur))
            ap, brier = [], []
            for name in groups[group]:
                run_dir = out / "runs" / name / f"blur{blur}"
                ap.append(cells(run_dir / "eval-kitti" / "results.json", cls)["ap_r40"] / 100)
                brier.append(cells(run_dir / "eval-optimal" / "results.json",
                                   cls)["brier"]["over_labels"])

            def mean_sd(v):  # undefined values (no labels: no Brier over labels) left out
                v = [x for x in v if x is not None]
                if not v:
                    return "n/a"
                mean = sum(v) / len(v)
                if len(v) == 1:
                    return f"{mean:.3f}"
                return f"{mean:.3f} ± {(sum((x - mean) ** 2 for x in v) / (len(v) - 1)) ** 0.5:.3f}"
            want = [group, blur, "2 of 2", mean_sd(ap), mean_sd(brier)]
            check(row == want, f"{cls} training variance {group} blur {blur}: {row} != {want}")
            checked += 1
# Per class: 14 model rows (6 image models x 2 blurs + 2 3D models), 14 paired rows, 4 variance.
check(checked == 3 * (14 + 14 + 4), f"checked 96 rows against their files (got {checked})")

# Verdicts, recomputed from the compares' bootstrap.csv.
with open(repo / "experiments" / "miniature_claims.csv") as f:
    claims = {c["claim"]: c for c in csv.DictReader(line for line in f if not line.startswith("#"))}
vrows = tables.get(("all", "verdicts"), [])
# One row per claim, the RPN claim (two seed pairs) once, decided by the rule over seeds.
check(sorted(r[0] for r in vrows) == sorted(claims),
      f"a verdict row per claim: {[r[0] for r in vrows]}")


def seeds_interval(seed_pairs, c, measure, root):
    """The rule over seeds and frames recomputed from the seed pairs' compares: the mean of their
    A - B, the frame term from the seed-averaged bootstrap_samples.csv (same resamples)."""
    estimates, resampled = [], []
    for a_name, b_name in seed_pairs:
        path = root / "compare" / f"{a_name}-vs-{b_name}" / f"blur{c['blur_sigma_px']}" / c["matcher"]
        with open(path / "bootstrap.csv") as f:
            row = [r for r in csv.DictReader(f) if r["class"] == c["class"] and r["metric"] == "2d"
                   and r["difficulty"] == "Moderate" and r["measure"] == measure][0]
        estimates.append(float(row["a_minus_b"]))
        with open(path / "bootstrap_samples.csv") as f:
            resampled.append([None if r["a_minus_b"] == "" else float(r["a_minus_b"])
                              for r in csv.DictReader(f) if r["class"] == c["class"]
                              and r["metric"] == "2d" and r["difficulty"] == "Moderate"
                              and r["measure"] == measure])
    check(len({len(r) for r in resampled}) == 1 and len(resampled[0]) == config["bootstrap"]["resamples"],
          f"bootstrap_samples.csv: one value per resample for {measure}")
    averaged = [sum(v) / len(v) for v in zip(*resampled) if None not in v]
    mean = sum(averaged) / len(averaged)
    variance = sum((x - mean) ** 2 for x in averaged) / (len(averaged) - 1)
    _, lo, hi, _ = verdict_rule.combined_interval(estimates, variance, len(averaged) - 1)
    return lo, hi


def set_verdict(root, c, row):
    """The verdict claim `c` gets on one set (the experiment folder `root`: OUT, or
    OUT/replication for the replication set), recomputed from its files."""
    if c["measure"].startswith("sweep_"):
        # A sweep claim: the share of swept values where stable is above naive, recounted from
        # sweep.csv; confirmed at 80 % or more, refuted below 50 %.
        measure = c["measure"][len("sweep_"):]
        with open(root / "figures" / f"sweep-{c['a']}" / "sweep.csv") as f:
            d = [float(r[f"stable_{measure}"]) - float(r[f"naive_{measure}"])
                 for r in csv.DictReader(f) if r["class"] == c["class"]
                 and r[f"stable_{measure}"] != "" and r[f"naive_{measure}"] != ""]
        share = sum(x > 1e-12 for x in d) / len(d) if d else None
        text = f"{sum(x > 1e-12 for x in d)} / {len(d)} = "
        return ("confirmed" if share is not None and share >= 0.8 else
                "refuted" if share is not None and share < 0.5 else "inconclusive"), text
    pair_text = row[1].split(",")[0].strip()
    a_name, b_name = pair_text.split(" - ")
    if len(groups.get(a_name, [])) > 1 and len(groups.get(a_name, [])) == len(groups.get(b_name, [])):
        # A claim on seeds: the combined interval of every measure, its side of 0.
        sides = []
        for measure in c["measure"].split("/"):
            lo, hi = seeds_interval(list(zip(groups[a_name], groups[b_name])), c, measure, root)
            sides.append(0 if lo <= 0 <= hi else 1 if lo > 0 else -1)
        if 0 in sides:
            return "inconclusive", "2 seed pairs"
        if c["expect"] == "flip":
            return ("confirmed" if sides[0] != sides[1] else "refuted"), "2 seed pairs"
        return ("confirmed" if (sides[0] > 0) == (c["expect"] == ">0") else "refuted"), \
            "2 seed pairs"
    if [a_name, b_name] not in config["pairs"]:
        return "not measured (the pair is not in this config)", ""
    if b_name == "ssd-absent":
        return "not measured (missing: ssd-absent)", ""
    path = root / "compare" / f"{a_name}-vs-{b_name}" / f"blur{c['blur_sigma_px']}" / c["matcher"]
    with open(path / "bootstrap.csv") as f:
        by_measure = {r["measure"]: r for r in csv.DictReader(f) if r["class"] == c["class"]
                      and r["metric"] == "2d" and r["difficulty"] == "Moderate"}
    # Each measure's side of 0: +1, -1, or 0 when its interval holds 0.
    sides = []
    for measure in c["measure"].split("/"):
        lo = float(by_measure[measure]["a_minus_b_lower"])
        hi = float(by_measure[measure]["a_minus_b_upper"])
        sides.append(0 if lo <= 0 <= hi else 1 if lo > 0 else -1)
    if 0 in sides:
        return "inconclusive", ""
    if c["expect"] == "flip":  # two Brier terms: confirmed when they rank A, B oppositely
        return ("confirmed" if sides[0] != sides[1] else "refuted"), ""
    return ("confirmed" if (sides[0] > 0) == (c["expect"] == ">0") else "refuted"), ""


# Each claim's row: its verdict on each set, recomputed, and the rule of replication: confirmed or
# refuted where both sets say so, "not replicated" where they differ.
seen, flips_seen = set(), set()
for row in vrows:
    c = claims[row[0]]
    check(len(row) == 6, f"verdict row of {c['id']}: claim, decided by, two intervals, verdict, "
          f"change ({len(row)} cells)")
    if len(row) != 6:
        continue
    if not c["measure"].startswith("sweep_"):
        pair_text, blur = (x.strip() for x in row[1].split(",")[:2])
        check(pair_text.split(" - ")[0] == c["a"] and blur == f"blur {c['blur_sigma_px']}",
              f"verdict row {row[1]!r} is of claim {c['id']}")
    v1, how = set_verdict(out, c, row)
    v2, how2 = set_verdict(out / "replication", c, row)
    word1, word2 = v1.split(" (")[0], v2.split(" (")[0]
    want = v1 if word1 in ("not measured", word2) else \
        f"not replicated ({word1} on the first set, {word2} on the replication set)"
    check(row[4] == want, f"verdict of {c['id']} ({row[1]}): {row[4]!r} != {want!r}")
    check(how in row[2] and how2 in row[3], f"verdict of {c['id']}: intervals {row[2:4]} "
          f"show {how!r}, {how2!r}")
    if c["expect"] == "flip" and word1 != "inconclusive":
        flips_seen.add(word1)
    seen.add(word1)
    seen.add(row[4].split(" (")[0])
check(seen >= {"confirmed", "refuted", "inconclusive", "not measured"},
      f"the miniature's claims cover every verdict: {sorted(seen)}")
check(flips_seen, "a flip claim of the miniature is decided (confirmed or refuted)")

# Percentile against BCa: one row per claim, seed pair and measure (the 5 BCa compares: 13 rows),
# each interval the one its compare folder's bootstrap.csv holds.
brows = tables.get(("all", "bca"), [])
check(len(brows) == 13, f"a BCa row per claim, seed pair and measure: {len(brows)}")
for row in brows:
    c = [x for x in claims.values() if x["id"] == row[0]][0]
    a_name, b_name = row[1].split(" - ")
    scale = 0.01 if row[2] == "ap_r40" else 1.0
    for col, matcher in ((3, c["matcher"]), (5, c["matcher"] + "-bca")):
        with open(out / "compare" / f"{a_name}-vs-{b_name}" / f"blur{c['blur_sigma_px']}" / matcher
                  / "bootstrap.csv") as f:
            r = [r for r in csv.DictReader(f) if r["class"] == c["class"] and r["metric"] == "2d"
                 and r["difficulty"] == "Moderate" and r["measure"] == row[2]][0]
        text = f"{float(r['a_minus_b']) * scale:+.3f}"
        if r["a_minus_b_lower"] != "":
            lo, hi = float(r["a_minus_b_lower"]) * scale, float(r["a_minus_b_upper"]) * scale
            text += f" [{lo:+.3f}, {hi:+.3f}]" + (" *" if lo > 0 or hi < 0 else "")
        check(row[col] == text, f"BCa row {row[:3]}: {matcher} {row[col]!r} != {text!r}")
# The power table: a row per claim and measure decided by an interval; the frames needed by a
# claim on one training recomputed from its interval (verdict_rule.power_needs).
prows = {(r[0], r[1]): r for r in tables.get(("all", "power"), [])}
check(len(prows) == 10, f"a power row per claim and measure: {sorted(prows)}")
row = prows.get(("ap-blurred", "ap_r40"))
with open(out / "compare" / "ssd-rgb-vs-ssd-rgbh-fixed" / "blur5" / "kitti" / "bootstrap.csv") as f:
    r = [r for r in csv.DictReader(f) if r["class"] == "Car" and r["metric"] == "2d"
         and r["difficulty"] == "Moderate" and r["measure"] == "ap_r40"][0]
effect = float(r["a_minus_b"]) / 100
width = (float(r["a_minus_b_upper"]) - float(r["a_minus_b_lower"])) / 100
_, frames_needed = verdict_rule.power_needs(effect, 0.0, (width / (2 * 1.959964)) ** 2, 2, 1, 1)
check(row is not None and row[6] == str(frames_needed) and row[5] == "n/a",
      f"power row of ap-blurred: {row}, frames needed {frames_needed}")
# By hand: effect 0.05, one training, frame se 0.02 at 1000 frames: 80 % power needs se <=
# 0.05 / (1.96 + 0.8416) = 0.017846, i.e. 1000 * (0.02 / 0.017846)^2 = 1256 frames.
check(verdict_rule.power_needs(0.05, 0.0, 0.0004, 1000, 999, 1) == (None, 1256),
      "power_needs by hand: 1256 frames")

# rpn-rgbd is initialised from rpn-rgb of its seed ({models}, {seed}): its training depends on it.
for seed in (1, 2):
    marker = json.loads((out / "steps" / f"train-rpn-rgbd-seed{seed}.json").read_text())
    check(f"train-rpn-rgb-seed{seed}" in marker["deps"] and
          str(out / "models" / f"rpn-rgb-seed{seed}") in marker["command"],
          f"train-rpn-rgbd-seed{seed}: --init-from its rgb model, a dependency: {marker}")

# The figures: one report per group, and the sweep's shares recounted from its sweep.csv.
for folder in ("models", "blur", "compare-det3d-lidar-vs-det3d-stereo", "sweep-ssd-rgb/report",
               "compression"):
    check((out / "figures" / folder / "index.html").is_file(), f"figures/{folder}/index.html")
compression_html = (out / "figures" / "compression" / "index.html")
compression_html = compression_html.read_text() if compression_html.is_file() else ""
check(all(label in compression_html for label in
          ("ssd-rgb blur0", "ssd-rgb blur5", "ssd-rgbh-fixed blur0", "ssd-rgbh-fixed blur5")),
      "figures.overlays: the compression report overlays both models sharp and blurred")
# (`eval sweep --report` has no --no-png: only the `stereodet report` folders follow the setting.)
check(not [p for p in (out / "figures").rglob("*.png") if "sweep-" not in str(p)],
      "figures.png false: no PNGs from stereodet report")
srows = {(r[0], r[1]): r for r in tables.get(("all", "sweep"), [])}
with open(out / "figures" / "sweep-ssd-rgb" / "sweep.csv") as f:
    sweep = list(csv.DictReader(f))
for cls in config["classes"]:
    values = [r for r in sweep if r["class"] == cls]
    row = srows.get(("ssd-rgb", cls))
    check(row is not None and row[3] == str(len(values)), f"sweep row for {cls}: {row}")
    for k, measure in ((4, "precision"), (5, "recall")):
        d = [float(r[f"stable_{measure}"]) - float(r[f"naive_{measure}"]) for r in values]
        counts = f"{sum(x > 1e-12 for x in d)} / {sum(abs(x) <= 1e-12 for x in d)} / " \
                 f"{sum(x < -1e-12 for x in d)}"
        check(row is not None and row[k].startswith(counts),
              f"sweep {cls} {measure}: {row[k] if row else None} vs {counts}")

# Calibration on a held-out split: the halves of the val split in split order; per model of
# calibration.models and method a calibration file fitted on the first half at the model's Table 1
# overlap kind (Moderate, optimal matcher); every row of the table equal to its held-out
# evaluation's results.json (the miniature's calibrated models have one training each).
METHODS = ("temperature", "platt", "isotonic")
val_ids = (out / "data" / "mini" / "ImageSets" / "val.txt").read_text().split()
halves = [(out / "splits" / "mini" / f"{h}.txt").read_text().split() for h in ("calib", "heldout")]
check(halves == [val_ids[:len(val_ids) // 2], val_ids[len(val_ids) // 2:]],
      f"the split's halves: {halves} of {val_ids}")
crows = {(r[0], r[1]): r for r in tables.get(("all", "calibration"), [])}
calibrated = [n for g in config["calibration"]["models"] for n in groups[g]]
check(len(crows) == 4 * len(calibrated), f"a calibration row per model and calibration: "
      f"{sorted(crows)}")
by_name = {m["name"]: m for m in config["models"]}
for name in calibrated:
    metric = METRIC[by_name[name]["family"]]
    for method in (None,) + METHODS:
        folder = out / "calibration" / name / f"heldout-{method or 'uncalibrated'}"
        results = json.loads((folder / "results.json").read_text())
        file = out / "calibration" / name / f"{method}.json" if method else None
        check((results["input"].get("calibration") or {}).get("file") == (str(file) if file else
                                                                           None) and
              f"--split {out / 'splits' / 'mini' / 'heldout.txt'} " in results["command_line"],
              f"{folder.name} of {name}: the held-out half, calibrated by {file}")
        if file:
            fitted = json.loads(file.read_text())["fitted_on"]
            want = {"metric": metric, "matcher": "optimal", "difficulty": "Moderate",
                    "method": method, "frames": str(len(halves[0])),
                    "split": str(out / "splits" / "mini" / "calib.txt")}
            check({k: fitted.get(k) for k in want} == want, f"{file}: fitted on {fitted}")
        c = cells(folder / "results.json", "Car", metric)
        values = [c["calibration"][k] for k in ("ece", "laece", "dece")] + \
            [c["brier"][k] for k in ("over_labels", "over_detections", "over_all")]
        want = [name, method or "none", metric, "1 of 1"] + \
            ["n/a" if v is None else f"{v:.4f}" for v in values]
        check(crows.get((name, method or "none")) == want,
              f"calibration row {name} {method}: {crows.get((name, method or 'none'))} != {want}")

# On Dask (a local cluster of 2 workers): the same steps, the same table and the same result
# files byte for byte as the run without Dask; a run without Dask then finds it all complete.
dask_out = work / "dask-out"


def run_to(out_dir, *extra, config_file=config_path):
    return subprocess.run([sys.executable, str(script), "--config", str(config_file), "--out",
                           str(out_dir), "--bin", str(bin_dir), *extra], capture_output=True,
                          text=True)


p = run_to(dask_out, "--workers", "2")
check(p.returncode == 0, f"Dask run: exit {p.returncode}: {p.stderr.strip()[-2000:]}")
dask_steps = sorted(re.findall(r"^==> ([\w.-]+):", p.stdout, re.M))
serial_steps = sorted(re.findall(r"^==> ([\w.-]+):", first.stdout, re.M))
check(dask_steps == serial_steps and len(re.findall(r"^<== ", p.stdout, re.M)) == steps,
      f"Dask run: the serial run's {steps} steps, each reported done")
check(p.returncode == 0 and (dask_out / "table1.md").read_text() == table_text,
      "Dask run: the same table1.md")
# The files that hold results, byte for byte: the trained weights, the detections, the
# bootstrap and sweep tables; results.json by its results (its provenance names its folders).
same_bytes = sorted(f.relative_to(out) for pattern in (
    "models/*/model.pt", "runs/*/*/detections/*.txt", "compare/**/*.csv",
    "figures/sweep-*/sweep.csv", "splits/*/*.txt") for f in out.glob(pattern))
results_json = sorted(f.relative_to(out) for pattern in ("runs/**/results.json",
                                                         "calibration/**/results.json")
                      for f in out.glob(pattern))
calibration_files = sorted(f.relative_to(out) for f in out.glob("calibration/*/*.json"))
check(len(same_bytes) > 40 and len(results_json) == 28 + 4 * len(calibrated) and
      len(calibration_files) == 3 * len(calibrated),
      f"the serial run's result files: {len(same_bytes)}, {len(results_json)} results.json, "
      f"{len(calibration_files)} calibration files")
differ = [str(f) for f in same_bytes if not (dask_out / f).is_file() or
          (dask_out / f).read_bytes() != (out / f).read_bytes()]
differ += [str(f) for f in results_json if not (dask_out / f).is_file() or
           json.loads((dask_out / f).read_text())["results"] !=
           json.loads((out / f).read_text())["results"]]
# A calibration file by its maps (its fitted_on names its folders).
differ += [str(f) for f in calibration_files if not (dask_out / f).is_file() or
           json.loads((dask_out / f).read_text())["classes"] !=
           json.loads((out / f).read_text())["classes"]]
check(not differ, f"Dask run: result files equal to the serial run's ({differ[:5]})")
p = run_to(dask_out)
check(f"0 steps run, {steps} skipped" in p.stdout, "a run without Dask resumes the Dask run's "
      f"folder: every step complete ({p.stdout.strip().splitlines()[-1:]})")
# A step that fails on Dask: the run exits 1 with its error, submits nothing that depends on it,
# and the steps that did run keep their markers.
failing_cfg = json.loads(config_path.read_text())
failing_cfg["models"] = [failing_cfg["models"][0], dict(failing_cfg["models"][1],
                                                        detect_flags=["--no-such-flag"])]
failing_cfg["pairs"], failing_cfg["claims"], failing_cfg["blur_sigmas_px"] = [], "", [0]
failing_cfg["figures"] = {"png": False}
failing_cfg["calibration"] = {"methods": []}
failing_path = work / "failing.json"
failing_path.write_text(json.dumps(failing_cfg))
p = run_to(work / "failing-out", "--workers", "2", config_file=failing_path)
bad_model = failing_cfg["models"][1]["name"]
check(p.returncode == 1 and "--no-such-flag" in p.stderr and
      f"eval-{bad_model}-blur0-kitti" not in p.stdout,
      f"a failing step on Dask: exit 1, its error, nothing after it ({p.returncode}, "
      f"{p.stderr.strip()[-300:]!r})")
check((work / "failing-out" / "steps" / f"detect-{failing_cfg['models'][0]['name']}-blur0.json")
      .is_file(), "a failing step on Dask: the steps that ran keep their markers")

# Resumable: a second run runs nothing and writes the same table; a lost marker reruns its step.
stamp = (out / "runs" / "ssd-rgb" / "blur0" / "eval-kitti" / "results.json").stat().st_mtime_ns
second = run()
check(f"0 steps run, {steps} skipped" in second.stdout, "second run skips every step")
check((out / "runs" / "ssd-rgb" / "blur0" / "eval-kitti" / "results.json").stat().st_mtime_ns
      == stamp, "second run leaves results.json alone")
check((out / "table1.md").read_text() == table_text, "second run writes the same table")
(out / "steps" / "detect-ssd-rgbh-fixed-blur5.json").unlink()
third = run()
rerun = sorted(re.findall(r"^==> ([\w.-]+):", third.stdout, re.M))
check(rerun == ["compare-ssd-rgb-vs-ssd-rgbh-fixed-blur5-kitti",
                "compare-ssd-rgb-vs-ssd-rgbh-fixed-blur5-kitti-bca",
                "compare-ssd-rgb-vs-ssd-rgbh-fixed-blur5-optimal",
                "compare-ssd-rgb-vs-ssd-rgbh-fixed-blur5-optimal-bca", "detect-ssd-rgbh-fixed-blur5",
                "eval-ssd-rgbh-fixed-blur5-kitti", "eval-ssd-rgbh-fixed-blur5-optimal",
                "report-blur", "report-compression"],
      f"a lost detection marker reruns it and what depends on it, only: {rerun}")
check((out / "table1.md").read_text() == table_text, "the rerun step gives the same table")

# A checkpoint replaced under the same path reruns its detections (and what depends on them).
ckpt_cfg = json.loads(config_path.read_text())
ckpt = work / "ssd-copy"
shutil.copytree(repo / "models" / "ssd-rgb", ckpt)
ckpt_cfg["models"] = [dict(ckpt_cfg["models"][0], model=str(ckpt))]
ckpt_cfg["pairs"], ckpt_cfg["claims"], ckpt_cfg["blur_sigmas_px"] = [], "", [0]
ckpt_cfg["figures"]["overlays"] = {}
ckpt_cfg["calibration"] = {"models": ["ssd-rgb"]}
ckpt_path = work / "checkpoint.json"
ckpt_path.write_text(json.dumps(ckpt_cfg))


def run_ckpt():
    p = subprocess.run([sys.executable, str(script), "--config", str(ckpt_path), "--out",
                        str(work / "ckpt-out"), "--bin", str(bin_dir)], capture_output=True, text=True)
    check(p.returncode == 0, f"checkpoint run: {p.stderr.strip()}")
    return sorted(re.findall(r"^==> ((?:replication/)?[\w.-]+):", p.stdout, re.M))


run_ckpt()
check(run_ckpt() == [], "the checkpoint run skips everything the second time")
os.utime(ckpt / "model.pt", ns=(0, 12345))
rerun = run_ckpt()
check(rerun == sorted(["detect-ssd-rgb-blur0", "eval-ssd-rgb-blur0-kitti", "eval-ssd-rgb-blur0-optimal",
                       "report-models", "sweep-ssd-rgb", "heldout-ssd-rgb-uncalibrated"] +
                      [f"calibrate-ssd-rgb-{x}" for x in METHODS] +
                      [f"heldout-ssd-rgb-{x}" for x in METHODS] +
                      [f"replication/{x}" for x in ("detect-ssd-rgb-blur0", "eval-ssd-rgb-blur0-kitti",
                                                    "eval-ssd-rgb-blur0-optimal", "sweep-ssd-rgb")]),
      f"a replaced checkpoint reruns its detection, evaluations and figures on both sets: {rerun}")

# A "kitti" source: a data set in KITTI's layout that the experiment does not generate (the
# miniature's synthetic set, which synth writes in that layout). The same frames and checkpoints
# give the same rows as the synth run: an image detector, and a stereo 3D detector whose stereo
# points are computed from the root (a step without a data dependency).
kitti_cfg = json.loads(config_path.read_text())
kitti_cfg["datasets"] = {"real": {"source": "kitti", "root": str(out / "data" / "mini")}}
kitti_cfg["models"] = [dict(m, data="real") for m in kitti_cfg["models"]
                       if m["name"] in ("ssd-rgb", "det3d-stereo")]
kitti_cfg["pairs"], kitti_cfg["claims"], kitti_cfg["blur_sigmas_px"] = [], "", [0]
kitti_cfg["replication"] = {}
kitti_cfg["figures"] = {"png": False}
kitti_cfg["calibration"] = {"models": ["ssd-rgb", "det3d-stereo"]}
kitti_path = work / "kitti.json"
kitti_path.write_text(json.dumps(kitti_cfg))


def run_kitti(config_file):
    return subprocess.run([sys.executable, str(script), "--config", str(config_file), "--out",
                           str(work / "kitti-out"), "--bin", str(bin_dir)], capture_output=True,
                          text=True)


p = run_kitti(kitti_path)
check(p.returncode == 0, f"kitti source run: {p.stderr.strip()}")
kitti_steps = sorted(re.findall(r"^==> ([\w.-]+):", p.stdout, re.M))
check(not [s for s in kitti_steps if s.startswith("data-")] and "stereo-real-val" in kitti_steps,
      f"kitti source: no data step, stereo points from its root ({kitti_steps})")
kitti_tables = parse_tables((work / "kitti-out" / "table1.md").read_text()) \
    if p.returncode == 0 else {}
for cls in config["classes"]:
    synth_rows = {(r[0], r[1]): r for r in tables.get((cls, "table"), [])}
    kitti_rows = {(r[0], r[1]): r for r in kitti_tables.get((cls, "table"), [])}
    for name in ("ssd-rgb", "det3d-stereo"):
        a, b = synth_rows.get((name, "0")), kitti_rows.get((name, "0"))
        check(a is not None and b is not None and a[3:8] == b[3:8],
              f"kitti source {cls} {name}: the synth run's row {a}, the kitti run's {b}")
# The calibration rows too: the halves of the root's own ImageSets/val.txt, the same frames.
kitti_crows = {(r[0], r[1]): r for r in kitti_tables.get(("all", "calibration"), [])}
for name in ("ssd-rgb", "det3d-stereo"):
    for method in ("none",) + METHODS:
        a, b = crows.get((name, method)), kitti_crows.get((name, method))
        check(a is not None and a == b,
              f"kitti source calibration {name} {method}: the synth run's row {a}, the kitti's {b}")
# A root without training/ is refused before anything runs, naming the field.
kitti_cfg["datasets"]["real"]["root"] = str(work / "no-such-kitti")
kitti_path.write_text(json.dumps(kitti_cfg))
p = run_kitti(kitti_path)
check(p.returncode == 1 and "datasets.real.root:" in p.stderr and "no training/ folder" in p.stderr,
      f"kitti root without training/: {p.returncode} {p.stderr.strip()!r}")
# So is one without the evaluated split's ImageSets file.
no_split = work / "kitti-no-split"
(no_split / "training").mkdir(parents=True)
kitti_cfg["datasets"]["real"]["root"] = str(no_split)
kitti_path.write_text(json.dumps(kitti_cfg))
p = run_kitti(kitti_path)
check(p.returncode == 1 and "datasets.real.root:" in p.stderr and "ImageSets/val.txt" in p.stderr,
      f"kitti root without ImageSets/val.txt: {p.returncode} {p.stderr.strip()!r}")

# --table-only runs nothing; --update-docs replaces the marked section only.
doc = work / "RESULTS.md"
original = (repo / "docs" / "RESULTS.md").read_text()
doc.write_text(original)
run("--table-only", "--update-docs", str(doc))
new = doc.read_text()
begin = "<!-- BEGIN experiment table1: generated by scripts/experiment.py, do not edit -->"
end = "<!-- END experiment table1 -->"
check(new.split(begin)[0] == original.split(begin)[0] and
      new.split(end)[1] == original.split(end)[1], "--update-docs keeps the rest of the file")
check(table_text in new.split(begin)[1].split(end)[0], "--update-docs puts the table between")

# A compare made before bootstrap_samples.csv existed: --table-only says so in the claim's row
# (rerun the compares) instead of failing or deciding on the frames alone.
rpn_claim = [c for c in claims.values() if len(groups.get(c["a"], [])) > 1][0]
samples_file = (out / "compare" / f"{groups[rpn_claim['a']][0]}-vs-{groups[rpn_claim['b']][0]}" /
                f"blur{rpn_claim['blur_sigma_px']}" / rpn_claim["matcher"] / "bootstrap_samples.csv")
check(samples_file.exists(), f"the seed pairs' compares wrote {samples_file}")
moved = samples_file.with_suffix(".moved")
samples_file.rename(moved)
run("--table-only")
stale = (out / "table1.md").read_text()
moved.rename(samples_file)
check("not measured (no bootstrap_samples.csv: rerun the compares without --table-only)" in stale,
      "a claim on seeds without bootstrap_samples.csv is not measured, saying why")
run("--table-only")

# A config error names the file and the field.
bad = json.loads(config_path.read_text())
bad["models"][1]["family"] = "yolo"
bad_path = work / "bad.json"
bad_path.write_text(json.dumps(bad))
p = subprocess.run([sys.executable, str(script), "--config", str(bad_path), "--out", str(out),
                    "--bin", str(bin_dir)], capture_output=True, text=True)
check(p.returncode == 1 and f"{bad_path}: models[1].family: one of ssd, rpn, det3d, got 'yolo'"
      in p.stderr, f"config error names the field: {p.stderr.strip()!r}")

# Committed checkpoints per training seed ("seed_model"), without training: one model per seed,
# the first seed's checkpoint is "model", the others' come from the template; a template without
# {seed} is refused, naming the field.
spec = importlib.util.spec_from_file_location("experiment", script)
experiment = importlib.util.module_from_spec(spec)
spec.loader.exec_module(experiment)
seeded = json.loads(config_path.read_text())
seeded["train"] = False
for i, name in ((0, "ssd-rgb"), (1, "ssd-rgbh-fixed")):
    seeded["models"][i].update(seeds=[1, 3], train={"input": name[4:], "flags": []},
                               seed_model=f"models/{name}-seed{{seed}}")
seeded["pairs"] = [["ssd-rgb", "ssd-rgbh-fixed"], ["rpn-rgb", "rpn-rgbd"]]
seeded_path = work / "seeded.json"
seeded_path.write_text(json.dumps(seeded))
loaded = experiment.load_config(seeded_path)
by_name = {m["name"]: m for m in loaded["models"]}
check(loaded["groups"]["ssd-rgbh-fixed"] == ["ssd-rgbh-fixed-seed1", "ssd-rgbh-fixed-seed3"],
      f"seed_model: one model per seed ({loaded['groups']['ssd-rgbh-fixed']})")
check(by_name.get("ssd-rgbh-fixed-seed1", {}).get("model") == "models/ssd-rgbh-fixed" and
      by_name.get("ssd-rgbh-fixed-seed3", {}).get("model") == "models/ssd-rgbh-fixed-seed3",
      "seed_model: the first seed's checkpoint is the model, the others' the template's")
check(loaded["groups"]["rpn-rgb"] == ["rpn-rgb"], "without training a model without seed_model "
      "stays its one checkpoint")
check(loaded["pairs"][:2] == [["ssd-rgb-seed1", "ssd-rgbh-fixed-seed1"],
                              ["ssd-rgb-seed3", "ssd-rgbh-fixed-seed3"]],
      f"seed_model: one pair per seed ({loaded['pairs']})")
seeded["models"][1]["seed_model"] = "models/ssd-rgbh-fixed-seed"
seeded_path.write_text(json.dumps(seeded))
try:
    experiment.load_config(seeded_path)
    check(False, "seed_model without {seed} is refused")
except experiment.ConfigError as e:
    check(f"{seeded_path}: models[1].seed_model:" in str(e), f"seed_model error names it: {e}")

# A replication set that is not independent (the same generator seed), smaller, or missing for a
# data set a model uses is refused, naming the field.
for change, wanted in ((lambda c: c["datasets"]["mini-rep"].update(seed=1), "generator seed"),
                       (lambda c: c["datasets"]["mini-rep"].update(frames=2), "val frames, fewer"),
                       (lambda c: c.update(replication={}) or c["replication"].update(
                           {"mini-rep": "mini"}), "no replication set for mini")):
    rep_cfg = json.loads(config_path.read_text())
    change(rep_cfg)
    rep_path = work / "bad_replication.json"
    rep_path.write_text(json.dumps(rep_cfg))
    try:
        experiment.load_config(rep_path)
        check(False, f"replication config refused: {wanted}")
    except experiment.ConfigError as e:
        check(f"{rep_path}: replication" in str(e) and wanted in str(e),
              f"replication error names it ({wanted}): {e}")

# A calibration block with an unknown method, a class outside `classes` or an unknown model is
# refused, naming the field.
for change, field in ((dict(methods=["beta"]), "calibration.methods"),
                      (dict(classes=["Van"]), "calibration.classes"),
                      (dict(models=["no-such-model"]), "calibration.models")):
    cal_cfg = json.loads(config_path.read_text())
    cal_cfg["calibration"] = change
    cal_path = work / "bad_calibration.json"
    cal_path.write_text(json.dumps(cal_cfg))
    try:
        experiment.load_config(cal_path)
        check(False, f"calibration config refused: {change}")
    except experiment.ConfigError as e:
        check(f"{cal_path}: {field}:" in str(e), f"calibration error names {field}: {e}")

# A claim of an unknown kind is refused, naming the file, the claim and what it accepts.
header = "id,claim,a,b,blur_sigma_px,class,matcher,measure,expect,source\n"
for line, wanted in (
        ("f,x,ssd-rgb,ssd-rgbh-fixed,0,Car,optimal,brier_labels/ap_r40,flip,t",
         "claim 1 (f): expect 'flip' needs a measure of two Brier terms"),
        ("s,x,ssd-rgb,,0,Car,optimal,sweep_recall,>0,t",
         "claim 1 (s): a sweep measure (sweep_recall) needs expect 'share'"),
        ("m,x,ssd-rgb,ssd-rgbh-fixed,0,Car,optimal,ap_r11,<0,t", "claim 1 (m): expect '<0'")):
    bad_claims = work / "bad_claims.csv"
    bad_claims.write_text(header + line + "\n")
    try:
        experiment.read_claims(str(bad_claims))
        check(False, f"claim {line!r} is refused")
    except RuntimeError as e:
        check(f"{bad_claims}: {wanted}" in str(e), f"claim error names it: {e}")

if failures:
    raise SystemExit(f"experiment.miniature: {len(failures)} failure(s)")
shutil.rmtree(work, ignore_errors=True)
print(f"experiment.miniature: {steps} steps in {m.group(3)} s, {checked} rows match their files, "
      f"{len(vrows)} verdicts, resumable, docs section replaced")
