#!/usr/bin/python3
"""Writes the view_small fixture (docs: README.md here): two KITTI-layout frames with a left image,
calibration, a LiDAR scan, labels and detections whose 2D boxes are the projections of their 3D
boxes. Standard library only; deterministic. Run from this folder: /usr/bin/python3 make_fixture.py"""
import math, os, struct, zlib

P2 = [[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791], [0, 0, 1, 0.002745884]]
W, H = 1242, 375
CALIB = """P0: 7.215377e+02 0 6.095593e+02 0 0 7.215377e+02 1.728540e+02 0 0 0 1 0
P1: 7.215377e+02 0 6.095593e+02 -3.875744e+02 0 7.215377e+02 1.728540e+02 0 0 0 1 0
P2: 7.215377e+02 0 6.095593e+02 4.485728e+01 0 7.215377e+02 1.728540e+02 2.163791e-01 0 0 1 2.745884e-03
P3: 7.215377e+02 0 6.095593e+02 -3.395242e+02 0 7.215377e+02 1.728540e+02 2.199936e+00 0 0 1 2.729905e-03
R0_rect: 1 0 0 0 1 0 0 0 1
Tr_velo_to_cam: 0 -1 0 0 0 0 -1 0 1 0 0 0
Tr_imu_to_velo: 1 0 0 0 0 1 0 0 0 0 1 0
"""

def corners(h, w, l, x, y, z, ry):
    c, s = math.cos(ry), math.sin(ry)
    out = []
    for dy in (0, -h):
        for dx, dz in ((l / 2, w / 2), (l / 2, -w / 2), (-l / 2, -w / 2), (-l / 2, w / 2)):
            out.append((x + c * dx + s * dz, y + dy, z - s * dx + c * dz))
    return out

def project(p):
    u = [sum(P2[r][i] * v for i, v in enumerate((*p, 1.0))) for r in range(3)]
    return u[0] / u[2], u[1] / u[2]

def obj(kind, h, w, l, x, y, z, ry, score=None):
    uv = [project(p) for p in corners(h, w, l, x, y, z, ry)]
    x1, y1 = max(0, min(u for u, _ in uv)), max(0, min(v for _, v in uv))
    x2, y2 = min(W - 1, max(u for u, _ in uv)), min(H - 1, max(v for _, v in uv))
    alpha = ry - math.atan2(x, z)
    line = f"{kind} 0.00 0 {alpha:.2f} {x1:.2f} {y1:.2f} {x2:.2f} {y2:.2f} {h:.2f} {w:.2f} {l:.2f} {x:.2f} {y:.2f} {z:.2f} {ry:.2f}"
    return line + (f" {score:.2f}" if score is not None else "")

CAR = (1.5, 1.6, 3.9)
FRAMES = {
    "000000": {
        "labels": [obj("Car", *CAR, -3.0, 1.7, 12.0, 0.1), obj("Car", *CAR, 4.0, 1.7, 22.0, -0.3),
                   obj("Pedestrian", 1.8, 0.6, 0.8, 1.0, 1.7, 9.0, 0.0)],
        # a TP on the first car, a ghost, a poor box near the second car (IoU < 0.7: FP, and FN)
        "dets": [obj("Car", *CAR, -2.9, 1.7, 12.2, 0.12, 0.91), obj("Car", *CAR, -9.0, 1.7, 30.0, 0.5, 0.62),
                 obj("Car", *CAR, 5.2, 1.7, 22.5, -0.3, 0.44)],
    },
    "000001": {
        "labels": [obj("Car", *CAR, 2.0, 1.7, 15.0, 1.2)],
        "dets": [obj("Car", *CAR, 2.05, 1.7, 15.1, 1.2, 0.88), obj("Car", *CAR, -6.0, 1.7, 25.0, 0.0, 0.7),
                 obj("Car", *CAR, 7.0, 1.7, 35.0, 0.3, 0.35)],
    },
}

def png(path, rows):
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    open(path, "wb").write(data)

for d in ("label_2", "calib", "image_2", "velodyne", "det"):
    os.makedirs(d, exist_ok=True)
for fid, f in FRAMES.items():
    open(f"label_2/{fid}.txt", "w").write("\n".join(f["labels"]) + "\n")
    open(f"det/{fid}.txt", "w").write("\n".join(f["dets"]) + "\n")
    open(f"calib/{fid}.txt", "w").write(CALIB)
    # Sky above the horizon, road below: flat colours so that boxes stand out and the file is small.
    sky, road = (200, 200, 200) * W, (120, 120, 120) * W
    png(f"image_2/{fid}.png", [sky if v < 173 else road for v in range(H)])
    # LiDAR: the ground every metre (velo frame: x forward, y left, z up; ground at z = -1.7) and
    # each label's box sides, 0.25 m apart.
    pts = [(float(x), float(y), -1.7, 0.2) for x in range(3, 60) for y in range(-20, 21, 2)]
    for line in f["labels"]:
        v = line.split()
        h, w, l, x, y, z, ry = map(float, v[8:15])
        for i in range(4):
            a, b = corners(h, w, l, x, y, z, ry)[i], corners(h, w, l, x, y, z, ry)[(i + 1) % 4]
            for k in range(8):
                t = k / 8
                cx, cz = a[0] + t * (b[0] - a[0]), a[2] + t * (b[2] - a[2])
                for dy in (0.3, 0.8, 1.2):
                    pts.append((cz, -cx, -(y - dy), 0.8))  # cam (x, y, z) -> velo (z, -x, -y)
    with open(f"velodyne/{fid}.bin", "wb") as out:
        for p in pts:
            out.write(struct.pack("<4f", *p))
