#!/usr/bin/env python3
"""The servo service checked on the drive (issue 37): examples/ros/servo_depths_client's CSV (one row
per feature per image: stamp,id,u,v,depth,sigma,status,converged, the answers of yawdepth_node's
~depths) against make_drive_bag's truth wall: each converged depth against the depth of the wall
along the pixel's ray in that image's true camera.

    check_servo_depths.py TRUTH.json DEPTHS.csv

Prints rows, images answered, converged answers, their median relative error and the fraction within
3 sigma; exits 1 when a bound below is missed (standard library only).
"""
import csv
import statistics
import sys

import drive_truth

MIN_IMAGES_ANSWERED = 0.7   # of the bag's images after the first second: the service answered (the node
                            # needs its camera, mount and the motion around each stamp; the client drops
                            # none on an idle machine, a loaded one may)
MIN_CONVERGED_LATE = 0.8    # of the answers in the second half of the drive: converged (sigma/Z < 10 %)
MAX_MEDIAN_REL = 0.01       # median |Z - Z_true| / Z_true of the converged answers (the node's clouds: 0.06 %)
MIN_WITHIN_3SIGMA = 0.9     # converged answers within 3 sigma of the truth


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    truth = drive_truth.load(sys.argv[1])
    K = truth["intrinsics"]
    n, d = truth["wall"]["n"], truth["wall"]["d"]
    find = drive_truth.image_by_stamp(truth)
    rows, unknown, answered, late, late_converged = 0, 0, set(), 0, 0
    errors, within = [], 0
    t_first = min(im["stamp"] for im in truth["images"])
    t_last = max(im["stamp"] for im in truth["images"])
    with open(sys.argv[2]) as f:
        for r in csv.DictReader(f):
            rows += 1
            stamp = float(r["stamp"])
            image = find(stamp)
            if image is None:
                unknown += 1
                continue
            answered.add(image["index"])
            converged = r["converged"] == "1"
            if stamp > (t_first + t_last) / 2:
                late += 1
                late_converged += converged
            if not converged:
                continue
            # The wall's depth along the pixel's ray (pinhole: the drive's camera has no distortion).
            ray_c = [(float(r["u"]) - K["cx"]) / K["fx"], (float(r["v"]) - K["cy"]) / K["fy"], 1.0]
            R, t = drive_truth.rot(image["q"]), image["t"]
            z_true = (d - drive_truth.dot(n, t)) / drive_truth.dot(n, drive_truth.apply(R, ray_c))
            z, sigma = float(r["depth"]), float(r["sigma"])
            errors.append(abs(z - z_true) / z_true)
            within += abs(z - z_true) <= 3 * sigma
    images_after_1s = sum(1 for im in truth["images"] if im["stamp"] > t_first + 1.0)
    answered_after_1s = sum(1 for im in truth["images"] if im["stamp"] > t_first + 1.0 and im["index"] in answered)
    median_rel = statistics.median(errors) if errors else float("nan")
    print("servo client (~depths): %d rows, %d images answered (%d of %d after the first second), "
          "%d converged answers, median |error|/Z %.3f %%, within 3 sigma %.1f %%, converged in the second half %d of %d"
          % (rows, len(answered), answered_after_1s, images_after_1s, len(errors), 100 * median_rel,
             100 * within / max(len(errors), 1), late_converged, late))
    failures = []
    if unknown:
        failures.append("%d rows with a stamp of no image" % unknown)
    if answered_after_1s < MIN_IMAGES_ANSWERED * images_after_1s:
        failures.append("answers for %d of %d images after the first second (< %.0f %%)"
                        % (answered_after_1s, images_after_1s, 100 * MIN_IMAGES_ANSWERED))
    if late == 0 or late_converged < MIN_CONVERGED_LATE * late:
        failures.append("converged %d of %d answers in the second half (< %.0f %%)"
                        % (late_converged, late, 100 * MIN_CONVERGED_LATE))
    if not errors or not median_rel <= MAX_MEDIAN_REL:
        failures.append("median relative error %.3f %% (> %.1f %%)" % (100 * median_rel, 100 * MAX_MEDIAN_REL))
    if errors and within < MIN_WITHIN_3SIGMA * len(errors):
        failures.append("within 3 sigma %d of %d (< %.0f %%)" % (within, len(errors), 100 * MIN_WITHIN_3SIGMA))
    for f in failures:
        print("check_servo_depths: FAIL: " + f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
