#!/usr/bin/env python3
"""One table row: a `yawdepth measure` result of the drive against the rendering's truth.

    compare.py NAME MOTION_CSV POINTS_CSV REPORT_DIR MEASURE_STDERR SIM_DIR STAMPS_CSV [wall]

MOTION_CSV is the frame-based log measure read (simulate's own, or import-bag's); its image column
names each frame's image, either simulate's frame_NNNN.png or import-bag's <stamp ns>.png, which
STAMPS_CSV (drive_plan.py's) maps back to the rendered frame. Each ok point is compared, in the
camera frame of the image it is expressed at, with the true point: the board corner of truth.csv
moved through the true poses (motion_truth.csv, the rig of the truth: camera_offset, read from
SIM_DIR's first camera frame in truth.csv). Prints: input, images in the log, images where the board
was found, points ok, depth RMSE (mm), median |depth error| / sigma_zc, the RMS distance of the board's corners from
their true places in the world (mm), block length median (mm).
With `wall` the points are natural features (`measure --features klt`) on the textured wall the
board hangs on: each ok point's true depth is where its ray (from the true camera, through the
measured point) meets the board's plane (fitted exactly through the true corners). Prints: input,
images in the log, points, points ok, depth RMSE (mm), median |depth error| / sigma_zc, the share
of ok points within 2 sigma_zc, the largest |depth error| / depth (%), the warnings measure printed.
Standard library only.
"""
import csv
import math
import os
import re
import statistics
import sys


def roty(a):
    c, s = math.cos(a), math.sin(a)
    return [[c, 0, s], [0, 1, 0], [-s, 0, c]]


def mv(R, v):
    return [sum(R[i][k] * v[k] for k in range(3)) for i in range(3)]


def mtv(R, v):
    return [sum(R[k][i] * v[k] for k in range(3)) for i in range(3)]


def main():
    name, motion, points, report, err, sim, stamps = sys.argv[1:8]
    truth_motion = {int(r["frame"]): r for r in csv.DictReader(open(os.path.join(sim, "motion_truth.csv")))}
    by_image, by_stamp, by_exposure = {}, {}, {}
    for r in csv.DictReader(open(stamps)):
        by_image[r["image"]] = int(r["frame"])
        by_stamp[int(r["stamp_ns"])] = int(r["frame"])
        by_exposure[int(r["exposure_ns"]) // 1000000] = int(r["frame"])

    def rendered_frame(row):
        """The rendered frame of a log row: by simulate's image name, by an image named by its stamp
        in ns, else by the row's motion time t (the exposure, to the millisecond)."""
        name = os.path.basename(row["image"])
        stem = os.path.splitext(name)[0]
        if name in by_image:
            return by_image[name]
        if stem.isdigit() and int(stem) in by_stamp:
            return by_stamp[int(stem)]
        if row.get("t"):
            ms = round(float(row["t"]) * 1000)
            if ms in by_exposure:
                return by_exposure[ms]
        raise SystemExit(f"compare.py: {motion}: frame {row['frame']}: image {row['image']} is no rendered frame")

    frame_of = {}  # the measured log's frame -> the rendered frame
    n_images = 0
    for r in csv.DictReader(open(motion)):
        if r.get("image"):
            n_images += 1
            frame_of[int(r["frame"])] = rendered_frame(r)

    def pose(k):
        r = truth_motion[k]
        return roty(float(r["heading"])), [float(r[c]) for c in "xyz"], float(r["yaw"])

    # The true corners in the world, and the camera offset (truth.csv has both frames of each point).
    world, offset = {}, None
    for r in csv.DictReader(open(os.path.join(sim, "truth.csv"))):
        R, p, yaw = pose(int(r["frame"]))
        v = [float(r[c]) for c in "xyz"]
        c = [float(r[c]) for c in ("xc", "yc", "zc")]
        world[int(r["id"])] = [a + b for a, b in zip(mv(R, v), p)]
        if offset is None:  # v = R_y(yaw) (c + t0)
            offset = [a - b for a, b in zip(mtv(roty(yaw), v), c)]

    if len(sys.argv) > 8 and sys.argv[8] == "wall":
        wall_row(name, points, err, world, offset, pose, frame_of, n_images)
        return
    errors, ratios, ok = [], [], 0
    for r in csv.DictReader(open(points)):
        if r["status"] != "ok":
            continue
        ok += 1
        k = frame_of[int(r["frame"])]
        R, p, yaw = pose(k)
        v = mtv(R, [a - b for a, b in zip(world[int(r["id"])], p)])
        zc = mtv(roty(yaw), v)[2] - offset[2]
        e = float(r["zc"]) - zc
        errors.append(e)
        ratios.append(abs(e) / float(r["sigma_zc"]) if float(r["sigma_zc"]) > 0 else float("inf"))
    found, block = "?", "-"
    rep = os.path.join(report, "report.txt")
    text = open(err).read() + (open(rep).read() if os.path.exists(rep) else "")
    m = re.search(r"(\d+) of (\d+) frames", text)
    if m:
        found = m.group(1)
    m = re.search(r"all block lengths:\s*median ([0-9.]+) mm", text)
    if m:
        block = m.group(1)
    # The board in the motion log's world (plane.csv): simulate's world is the bags' odom frame, so
    # the true corners are comparable there; a wrong time offset moves it (40 ms at 0.1 m/s: 4 mm)
    # where at constant velocity the depths cannot tell.
    werr = []
    plane = os.path.join(report, "plane.csv")
    if os.path.exists(plane):
        for r in csv.DictReader(open(plane)):
            d = [float(r[c]) - t for c, t in zip("xyz", world[int(r["id"])])]
            werr.append(sum(x * x for x in d))
    wrms = math.sqrt(sum(werr) / len(werr)) * 1000 if werr else float("nan")
    rmse = math.sqrt(sum(e * e for e in errors) / len(errors)) * 1000 if errors else float("nan")
    med = statistics.median(ratios) if ratios else float("nan")
    print(f"| {name} | {n_images} | {found} | {ok} | {rmse:.3f} | {med:.2f} | {wrms:.2f} | {block} |")


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def wall_row(name, points, err, world, offset, pose, frame_of, n_images):
    """The natural features' row: each ok point against the wall plane through the true corners."""
    ids = sorted(world)
    q = world[ids[0]]
    normal = max((cross(sub(world[a], q), sub(world[b], q)) for a in ids for b in ids),
                 key=lambda n: dot(n, n))  # the two corners spanning the largest triangle with the first
    errors, ratios, rel, total, ok = [], [], [], 0, 0
    for r in csv.DictReader(open(points)):
        total += 1
        if r["status"] != "ok":
            continue
        ok += 1
        R, p, yaw = pose(frame_of[int(r["frame"])])
        c = [float(r[k]) for k in ("xc", "yc", "zc")]
        to_world = lambda cam: [a + b for a, b in zip(mv(R, mv(roty(yaw), [x + t for x, t in zip(cam, offset)])), p)]
        centre, through = to_world([0, 0, 0]), to_world(c)
        s = dot(normal, sub(q, centre)) / dot(normal, sub(through, centre))  # the ray meets the wall at s
        e = c[2] - s * c[2]
        errors.append(e)
        ratios.append(abs(e) / float(r["sigma_zc"]) if float(r["sigma_zc"]) > 0 else float("inf"))
        rel.append(abs(e) / (s * c[2]))
    warnings = sum(1 for line in open(err) if "warning:" in line)
    rmse = math.sqrt(sum(e * e for e in errors) / len(errors)) * 1000 if errors else float("nan")
    med = statistics.median(ratios) if ratios else float("nan")
    within = sum(1 for x in ratios if x <= 2) / len(ratios) if ratios else float("nan")
    worst = max(rel) * 100 if rel else float("nan")
    print(f"| {name} | {n_images} | {total} | {ok} | {rmse:.3f} | {med:.2f} | {within:.2f} | {worst:.2f} | {warnings} |")


if __name__ == "__main__":
    main()
