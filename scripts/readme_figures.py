#!/usr/bin/env python3
"""The figures the README quotes, from the commands that make them (issue 35).

    scripts/readme_figures.py measure BUILD_DIR WORK_DIR   # run the README's commands, full size
    scripts/readme_figures.py write                        # README.md's figures from the JSON
    scripts/readme_figures.py check                        # README.md agrees with the JSON

`measure` runs what the README's examples and its "What the training example gives" paragraph
describe, at the README's sizes: `synth --frames 200 --seed 7`, `stereo` at the models' scale,
`train ssd --input rgbh-learned` on its train split (the default 10 epochs), that model's and the
committed models' (models/ssd-rgbh-learned, models/ssd-rgb) detections on the val split and their
Car 2D AP_R40 (KITTI matcher), and the disk each output takes. It writes the figures, with the
date and the machine, to docs/readme_figures.json, then `write`s them into README.md.

`write` replaces the README's block between <!-- readme-figures:begin --> and
<!-- readme-figures:end --> with the text rendered from docs/readme_figures.json; `check` (run by
`make test`, cli.readme.figures) fails when the README's block is not that text, so a figure in
the README can only come from a measurement. Standard library only (Debian's /usr/bin/python3).
"""
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import textwrap
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
README = os.path.join(REPO, "README.md")
FIGURES = os.path.join(REPO, "docs", "readme_figures.json")
BEGIN, END = "<!-- readme-figures:begin -->", "<!-- readme-figures:end -->"


def run(args, **kwargs):
    """Runs a command, echoing it; returns (stdout + stderr, seconds)."""
    print("$ " + " ".join(str(a) for a in args), flush=True)
    start = time.monotonic()
    done = subprocess.run([str(a) for a in args], capture_output=True, text=True, check=False,
                          **kwargs)
    seconds = time.monotonic() - start
    if done.returncode != 0:
        sys.exit(f"readme_figures: exit {done.returncode}: {done.stdout}{done.stderr}")
    return done.stdout + done.stderr, seconds


def disk_mb(path):
    """What a folder takes on disk, MB (du's blocks, as a user sees it)."""
    out = subprocess.run(["du", "-sk", path], capture_output=True, text=True, check=True).stdout
    return int(out.split()[0]) / 1024


def car_2d(results_json):
    """{"easy": AP, "moderate": AP, "hard": AP, "tp"/"fp"/"fn": at Moderate} of Car 2D, strict."""
    with open(results_json) as f:
        results = json.load(f)["results"]
    out = {}
    for r in results:
        if r["class"] != "Car" or r["metric"] != "2d" or r.get("overlaps", "strict") != "strict":
            continue
        level = r["difficulty"].lower()
        out[level] = round(r["ap_r40"], 2)
        if level == "moderate":
            for key in ("tp", "fp", "fn"):
                out[key] = r["at_threshold"][key]
    if set(out) < {"easy", "moderate", "hard"}:
        sys.exit(f"readme_figures: {results_json} has no Car 2D cells")
    return out


def measure(build_dir, work):
    stereodet = os.path.join(os.path.abspath(build_dir), "bin", "stereodet")
    synth, stereo, ssd = (os.path.join(work, n) for n in ("synth", "stereo", "ssd"))
    # The steps done so far (WORK/figures.json): a rerun after an interruption goes on from there.
    partial = os.path.join(work, "figures.json")
    if os.path.exists(partial):
        with open(partial) as f:
            figures = json.load(f)
    else:
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        figures = {"date": time.strftime("%Y-%m-%d"),
                   "machine": f"{os.cpu_count()}-core {platform.machine()} VM, other work beside"}

    def done(step, value):
        figures[step] = value
        with open(partial + ".tmp", "w") as f:
            json.dump(figures, f, indent=2)
        os.replace(partial + ".tmp", partial)

    if "synth" not in figures:
        _, seconds = run([stereodet, "synth", "--out", synth, "--frames", 200, "--seed", 7,
                          "--quiet"])
        done("synth", {"frames": 200, "minutes": round(seconds / 60, 1),
                       "disk_mb": round(disk_mb(synth))})
    if "stereo" not in figures:
        _, seconds = run([stereodet, "stereo", "--data", synth, "--out", stereo, "--encode",
                          "rgbh,points", "--match-scale", 0.5, "--quiet"])
        done("stereo", {"seconds": round(seconds), "disk_mb": round(disk_mb(stereo))})
    if "train" not in figures:
        measure_training(stereodet, synth, ssd, done)
    for name, model in (("trained", ssd), ("ssd-rgbh-learned", "models/ssd-rgbh-learned"),
                        ("ssd-rgb", "models/ssd-rgb")):
        if name in figures:
            continue
        det, out = os.path.join(work, "det-" + name), os.path.join(work, "eval-" + name)
        shutil.rmtree(det, ignore_errors=True)
        shutil.rmtree(out, ignore_errors=True)
        run([stereodet, "detect", "ssd", "--model", model, "--data", synth, "--split", "val",
             "--out", det, "--quiet"], cwd=REPO)
        run([stereodet, "eval", "--gt", synth, "--det", det, "--split", "val", "--metrics", "2d",
             "--out", out])
        done(name, car_2d(os.path.join(out, "results.json")))

    with open(FIGURES, "w") as f:
        json.dump(figures, f, indent=2)
        f.write("\n")
    print(f"wrote {FIGURES}")
    write()


def measure_training(stereodet, synth, ssd, done):
    """`train ssd` as the README runs it: its time and what its summary line says."""
    shutil.rmtree(ssd, ignore_errors=True)
    text, seconds = run([stereodet, "train", "ssd", "--data", synth, "--split", "train", "--input",
                         "rgbh-learned", "--out", ssd])
    m = re.search(r"trained \S+: (\d+) frames, epochs (\d+)/\d+ .* ([0-9.]+) s \(stereo ([0-9.]+) s\)",
                  text)
    if not m:
        sys.exit("readme_figures: no summary line in train ssd's output:\n" + text)
    done("train", {"frames": int(m.group(1)), "epochs": int(m.group(2)),
                   "minutes": round(seconds / 60, 1), "stereo_seconds": round(float(m.group(4)))})


def render(f):
    """The README's block, from the figures."""
    t, rgbh, rgb, tr = f["train"], f["ssd-rgbh-learned"], f["ssd-rgb"], f["trained"]
    order = "above" if rgb["moderate"] > rgbh["moderate"] else "below"
    intro = textwrap.fill(
        f"What the examples give (measured {f['date']} on a {f['machine']}, by "
        f"`scripts/readme_figures.py measure`, which writes these lines): `synth` writes the 200 "
        f"frames in {f['synth']['minutes']} min and {f['synth']['disk_mb']} MB (LiDAR scans are "
        f"most of it; `--no-lidar` leaves them empty), and `stereo` their RGB-H images and point "
        f"clouds in {f['stereo']['seconds']} s and {f['stereo']['disk_mb']} MB. `train ssd` trains "
        f"{t['epochs']} epochs on the {t['frames']} training frames in {t['minutes']} min (the "
        f"stereo pre-pass {t['stereo_seconds']} s of it) and its model scores "
        f"**{tr['moderate']:.2f}** Car 2D AP_R40 (IoU 0.7, Moderate): 100 frames are too few to "
        f"learn much. A training of fewer steps than the 100-step learning-rate warm-up says so in "
        f"a warning line. The committed models (`models/`, 3000 frames, "
        f"[docs/models.md](docs/models.md)) on the same validation frames:", width=100)
    outro = textwrap.fill(
        f"(`models/ssd-rgb`: {rgb['easy']:.2f} / {rgb['moderate']:.2f} / {rgb['hard']:.2f} on "
        f"these frames: RGB scores {order} RGB-H on these 100 frames; "
        f"[docs/RESULTS.md](docs/RESULTS.md) compares them on 1000 validation frames, with "
        f"intervals.)", width=100)
    return f"""{BEGIN}
{intro}

```sh
build/bin/stereodet detect ssd --model models/ssd-rgbh-learned --data /tmp/synth --split val --out /tmp/det-committed
build/bin/stereodet eval --gt /tmp/synth --det /tmp/det-committed --split val --metrics 2d
# class        kind   tau |             Easy Moderate     Hard |  (operating point at Moderate)
# Car          2d    0.70 | AP_R40     {rgbh['easy']:5.2f}    {rgbh['moderate']:5.2f}    {rgbh['hard']:5.2f} |  TP {rgbh['tp']} FP {rgbh['fp']} FN {rgbh['fn']} ...
```

{outro}
{END}"""


def readme_parts():
    with open(README, encoding="utf-8") as f:
        text = f.read()
    begin, end = text.find(BEGIN), text.find(END)
    if begin < 0 or end < begin:
        sys.exit(f"readme_figures: {README} has no {BEGIN} ... {END} block")
    return text[:begin], text[begin:end + len(END)], text[end + len(END):]


def load():
    with open(FIGURES) as f:
        return json.load(f)


def write():
    before, _, after = readme_parts()
    with open(README + ".tmp", "w", encoding="utf-8") as f:
        f.write(before + render(load()) + after)
    os.replace(README + ".tmp", README)
    print(f"wrote the figures into {README}")


def check():
    _, block, _ = readme_parts()
    if block != render(load()):
        print(f"FAILED: {README}'s figures are not those of {FIGURES}; run "
              "`scripts/readme_figures.py write` (or `measure` to measure them again)")
        return 1
    print("README figures: as measured in docs/readme_figures.json")
    return 0


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "measure":
        measure(sys.argv[2], sys.argv[3])
        return 0
    if len(sys.argv) == 2 and sys.argv[1] == "write":
        write()
        return 0
    if len(sys.argv) == 2 and sys.argv[1] == "check":
        return check()
    sys.exit(__doc__)


if __name__ == "__main__":
    sys.exit(main())
