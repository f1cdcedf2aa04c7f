#!/usr/bin/env python3
"""measure's points against make_drive_bag's truth wall (standard library only).

    check_measure_truth.py TRUTH.json POINTS.csv MEASURE.err [--min-ok 200] [--min-within 0.9]
                           [--max-median-rel 0.02] [--label TEXT] [--stats FILE]

POINTS.csv is `yawdepth measure`'s points output (docs/formats.md, "Points output"): one row per
feature at its last frame, `xc, yc, zc` the point in that frame's camera (camera_optical, REP 103
optical axes), `sigma_zc` its depth's 1-sigma. `frame` is the row of the imported motion.csv: the
images in stamp order from 0 when every image matched (checked on the import's summary in
MEASURE.err), so frame k is the truth's image k, whose camera pose in odom the truth gives.

Per ok point: the point in odom (odomMc * c_P), its distance to the wall (n.p = d, odom), the true
depth along its ray (where the ray meets the wall) and its relative error, and whether the depth is
within 3 sigma. Prints the numbers; exit 0 when the bounds hold, 1 when not, 2 on bad input.
"""
import argparse
import csv
import re
import sys

import drive_truth


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("truth")
    ap.add_argument("points")
    ap.add_argument("log")
    ap.add_argument("--label", default="measure")
    ap.add_argument("--min-ok", type=int, default=200)
    ap.add_argument("--min-within", type=float, default=0.9)
    ap.add_argument("--max-median-rel", type=float, default=0.02)
    ap.add_argument("--stats", help="also write 'OK MEDIAN_REL WITHIN_FRACTION' to this file")
    a = ap.parse_args()
    try:
        truth = drive_truth.load(a.truth)
        rows = list(csv.DictReader(open(a.points)))
        log = open(a.log).read()
    except (OSError, ValueError) as e:
        print(f"check_measure_truth: {e}", file=sys.stderr)
        return 2
    images = truth["images"]
    m = re.search(r"(\d+) matched", log)
    if not m or int(m.group(1)) != len(images):
        print(f"check_measure_truth: {a.label}: the import matched {m.group(1) if m else '?'} images, the truth has "
              f"{len(images)}: frame numbers would not be the truth's image indices", file=sys.stderr)
        return 2
    errors, statuses = [], {}
    for r in rows:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        if r["status"] != "ok":
            continue
        c_P = [float(r["xc"]), float(r["yc"]), float(r["zc"])]
        errors.append(drive_truth.camera_point_errors(truth, images[int(r["frame"])], c_P, float(r["sigma_zc"])))
    if not errors:
        print(f"{a.label}: no ok point (statuses: {statuses})")
        return 1
    ok, med_dist, med_rel, frac, med_rel_sigma, med_err_sigma = drive_truth.summary(errors)
    within = sum(e["within"] for e in errors)
    if a.stats:
        with open(a.stats, "w") as f:
            f.write(f"{ok} {med_rel:.9g} {frac:.9g}\n")
    print(f"{a.label}: {len(rows)} points, {ok} ok (statuses: {statuses}); median |distance to wall| "
          f"{1000 * med_dist:.2f} mm; median relative depth error {100 * med_rel:.3f} %; "
          f"within 3 sigma {within}/{ok} = {100 * frac:.1f} %; median sigma_zc/zc "
          f"{100 * med_rel_sigma:.3f} %, median |error|/sigma {med_err_sigma:.2f}")
    bad = []
    if ok < a.min_ok:
        bad.append(f"{ok} ok points < {a.min_ok}")
    if frac < a.min_within:
        bad.append(f"within 3 sigma {frac:.3f} < {a.min_within}")
    if med_rel >= a.max_median_rel:
        bad.append(f"median relative error {med_rel:.4f} >= {a.max_median_rel}")
    if bad:
        print(f"{a.label}: outside the bounds: " + "; ".join(bad))
        return 1
    print(f"{a.label}: within the bounds (>= {a.min_ok} ok, >= {100 * a.min_within:.0f} % within 3 sigma, "
          f"median relative error < {100 * a.max_median_rel:.1f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
