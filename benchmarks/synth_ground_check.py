#!/usr/bin/env python3
"""Compares the stereo ground fits (stereodet stereo's OUT/ground/ID.txt) with the synthetic
data's true planes (DATA/training/planes/ID.txt, the least-squares plane of the true ground where
the fit samples it): angle between the normals, camera-height (offset) error, per frame and in
summary (docs/synth.md).

    python3 benchmarks/synth_ground_check.py DATA OUT [--list]
"""
import math
import pathlib
import statistics
import sys


def read_truth(path):
    lines = [l for l in path.read_text().split("\n") if l.strip()]
    a, b, c, d = (float(x) for x in lines[-1].split())
    n = math.sqrt(a * a + b * b + c * c)
    return (a / n, b / n, c / n), d / n


def read_fit(path):
    for line in path.read_text().split("\n"):
        if line.startswith("fitted"):
            f = line.split()
            fields = {f[i]: f[i + 1:i + 4] for i in range(0, len(f) - 1)}
            normal = tuple(float(x) for x in fields["normal"][:3])
            return (f[1] == "1", normal, float(fields["offset_m"][0]),
                    float(fields["tilt_deg"][0]))
    raise ValueError(f"{path}: no 'fitted' line")


def main():
    data, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    rows = []
    for fit_path in sorted((out / "ground").glob("*.txt")):
        frame = fit_path.stem
        normal_t, d_t = read_truth(data / "training" / "planes" / f"{frame}.txt")
        fitted, normal_f, d_f, tilt_f = read_fit(fit_path)
        cos = max(-1.0, min(1.0, sum(x * y for x, y in zip(normal_t, normal_f))))
        angle = math.degrees(math.acos(cos))
        tilt_t = math.degrees(math.acos(max(-1.0, min(1.0, -normal_t[1]))))
        rows.append((frame, fitted, angle, d_f - d_t, tilt_t, tilt_f))
    angles = [r[2] for r in rows]
    heights = [abs(r[3]) for r in rows]
    print(f"frames {len(rows)}, fitted {sum(r[1] for r in rows)}")
    print(f"true tilt: mean {statistics.mean(r[4] for r in rows):.2f} deg, "
          f"max {max(r[4] for r in rows):.2f} deg")
    print(f"angle error: mean {statistics.mean(angles):.3f} deg, median "
          f"{statistics.median(angles):.3f}, max {max(angles):.3f} deg")
    print(f"|height error|: median {1000 * statistics.median(heights):.1f} mm, mean "
          f"{1000 * statistics.mean(heights):.1f} mm, max {1000 * max(heights):.1f} mm")
    worst = sorted(rows, key=lambda r: -r[2])[:5]
    print("largest angle errors: " + ", ".join(
        f"{r[0]} {r[2]:.2f} deg ({1000 * r[3]:+.0f} mm)" for r in worst))
    for threshold in (0.5, 1.0, 2.0):
        print(f"frames with angle error > {threshold} deg: {sum(a > threshold for a in angles)}")
    if "--list" in sys.argv:
        for r in rows:
            print(*r)


if __name__ == "__main__":
    main()
