#!/usr/bin/python3
"""ROS's camera_calibration against `yawdepth calibrate-camera` on real photos, on views left out.

    /usr/bin/python3 benchmarks/ros_calibration_compare.py --yawdepth build/tools/yawdepth \
        [--data /work/shared/data/franka-eye-in-hand] [--pattern 9x6:0.0236] [--distortion auto]

Leave-one-out: for each photo, both calibrate on the other photos (ROS: MonoCalibrator.cal(), its
non-GUI code path, with the flags of its cameracalibrator's defaults, --k-coefficients 2, i.e.
CALIB_FIX_K3; yawdepth: calibrate-camera, its PREFIX_ros.yaml), both camera files are read by ROS's
own parser (camera_calibration_parsers), and the photo left out is predicted: its corners
(cv2.findChessboardCorners + cornerSubPix 11x11, the same corners for both) are fitted with a board
pose only, the intrinsics fixed (solvePnP), and its reprojection RMS counted. Prints a table and
exits 1 when yawdepth's RMS over the views left out is larger than ROS's (2 on a usage error or a
failed run). Needs python3-camera-calibration, python3-camera-calibration-parsers, python3-opencv.
"""
import argparse
import glob
import math
import os
import subprocess
import sys
import tempfile

try:
    import cv2
    import numpy
    import camera_calibration_parsers
    from camera_calibration.calibrator import ChessboardInfo, MonoCalibrator
except ImportError as e:  # Debian's python3-camera-calibration does not depend on what it imports
    print("ros_calibration_compare: %s: apt-get install python3-opencv python3-cv-bridge python3-image-geometry "
          "python3-camera-calibration python3-camera-calibration-parsers" % e, file=sys.stderr)
    sys.exit(2)


def read_camera(path):
    """K (3x3), D and distortion_model of a camera_info YAML, by ROS's parser."""
    _, info = camera_calibration_parsers.readCalibration(path)
    return numpy.array(info.K, dtype=numpy.float64).reshape(3, 3), numpy.array(info.D, dtype=numpy.float64), \
        info.distortion_model


def board_corners(image, cols, rows):
    """OpenCV's corners of the board (None when not found), refined 11x11 as OpenCV's samples do."""
    ok, corners = cv2.findChessboardCorners(image, (cols, rows),
                                            cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not ok:
        return None
    cv2.cornerSubPix(image, corners, (11, 11), (-1, -1),
                     (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 1e-3))
    return corners.reshape(-1, 2).astype(numpy.float64)


def heldout_squared_errors(K, D, model, corners, cols, rows, square):
    """Sum of squared reprojection errors (px^2) and point count of a view, its pose fitted alone."""
    obj = numpy.array([[(j % cols) * square, (j // cols) * square, 0.0] for j in range(cols * rows)],
                      dtype=numpy.float64)
    if model == "equidistant":
        normalised = cv2.fisheye.undistortPoints(corners.reshape(-1, 1, 2), K, D[:4].reshape(4, 1))
        ok, r, t = cv2.solvePnP(obj, normalised.reshape(-1, 2), numpy.eye(3), None)
        proj, _ = cv2.fisheye.projectPoints(obj.reshape(-1, 1, 3), r, t, K, D[:4].reshape(4, 1))
    else:
        ok, r, t = cv2.solvePnP(obj, corners, K, D)
        proj, _ = cv2.projectPoints(obj, r, t, K, D)
    if not ok:
        raise RuntimeError("solvePnP failed")
    d = proj.reshape(-1, 2) - corners
    return float((d * d).sum()), len(corners)


def ros_calibration(images, cols, rows, square, out):
    """ROS's MonoCalibrator on the images, written with its own yaml() to `out`."""
    board = ChessboardInfo("chessboard", cols, rows, square)
    calibrator = MonoCalibrator([board], cv2.CALIB_FIX_K3)  # cameracalibrator.py's default: 2 k-coefficients
    devnull = open(os.devnull, "w")
    stdout, sys.stdout = sys.stdout, devnull  # cal() prints "mono pinhole calibration..."
    try:
        calibrator.cal(images)
    finally:
        sys.stdout = stdout
        devnull.close()
    with open(out, "w") as f:
        f.write(calibrator.yaml())
    return len(calibrator.good_corners) if calibrator.good_corners else len(images)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--yawdepth", default=os.path.join(here, "..", "build", "tools", "yawdepth"))
    shared = "/work/shared/data/franka-eye-in-hand"  # the same 8 photos as tests/data's copy
    ap.add_argument("--data", default=shared if os.path.isdir(shared) else
                    os.path.join(here, "..", "tests", "data", "franka-eye-in-hand"))
    ap.add_argument("--images", default="franka_image-*.png", help="glob in --data")
    ap.add_argument("--pattern", default="9x6:0.0236", help="COLSxROWS:SQUARE, inner corners, metres")
    ap.add_argument("--distortion", default="auto", help="calibrate-camera's --distortion")
    a = ap.parse_args()
    try:
        size, square = a.pattern.split(":")
        cols, rows = (int(v) for v in size.lower().split("x"))
        square = float(square)
    except ValueError:
        print("--pattern '%s': expected COLSxROWS:SQUARE" % a.pattern, file=sys.stderr)
        return 2
    paths = sorted(glob.glob(os.path.join(a.data, a.images)),
                   key=lambda p: (len(p), p))
    if len(paths) < 4:
        print("%s: %d images, at least 4 are needed" % (a.data, len(paths)), file=sys.stderr)
        return 2
    gray = [cv2.imread(p, cv2.IMREAD_GRAYSCALE) for p in paths]
    corners = [board_corners(g, cols, rows) for g in gray]
    rows_out = []
    sums = {"ros": [0.0, 0], "ours": [0.0, 0]}
    with tempfile.TemporaryDirectory(prefix="ros_compare_") as tmp:
        for i, path in enumerate(paths):
            if corners[i] is None:
                print("%s: no board found, not used as a view left out" % path, file=sys.stderr)
                continue
            train = [j for j in range(len(paths)) if j != i]
            ros_file = os.path.join(tmp, "ros_%d.yaml" % i)
            ros_calibration([gray[j] for j in train], cols, rows, square, ros_file)
            prefix = os.path.join(tmp, "ours_%d" % i)
            run = subprocess.run([a.yawdepth, "calibrate-camera", "--quiet", "--pattern",
                                  "chessboard:%dx%d:%g" % (cols, rows, square), "--distortion", a.distortion,
                                  "--out", prefix] + [paths[j] for j in train],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
            if run.returncode != 0:
                print("yawdepth calibrate-camera failed: %s" % run.stderr.strip(), file=sys.stderr)
                return 2
            row = [os.path.basename(path)]
            for who, f in (("ros", ros_file), ("ours", prefix + "_ros.yaml")):
                K, D, model = read_camera(f)
                sse, n = heldout_squared_errors(K, D, model, corners[i], cols, rows, square)
                sums[who][0] += sse
                sums[who][1] += n
                row += [model, math.sqrt(sse / n)]
            rows_out.append(row)
    if not rows_out:
        print("no view left out had a board", file=sys.stderr)
        return 2
    ros = math.sqrt(sums["ros"][0] / sums["ros"][1])
    ours = math.sqrt(sums["ours"][0] / sums["ours"][1])
    print("Held-out reprojection RMS (px), leave-one-out over %d photos of %s, board %dx%d, %g m:"
          % (len(paths), a.data, cols, rows, square))
    print("%-20s %-22s %s" % ("view left out", "ROS camera_calibration", "yawdepth calibrate-camera"))
    for name, rm, rr, om, orr in rows_out:
        print("%-20s %8.4f %-13s %8.4f %s" % (name, rr, rm, orr, om))
    print("%-20s %8.4f %-13s %8.4f" % ("all views left out", ros, "", ours))
    verdict = "yawdepth better" if ours < ros else "ROS better" if ours > ros else "equal"
    print("%s: %.1f %% of ROS's held-out RMS" % (verdict, 100.0 * ours / ros))
    return 0 if ours <= ros else 1


if __name__ == "__main__":
    sys.exit(main())
