"""make_drive_bag's truth (its --truth JSON) and points checked against its wall (standard library only).

Shared by check_measure_truth.py (`yawdepth measure`'s points) and check_node_clouds.py (the ROS node's
clouds). The truth: the wall in odom (n.p = d) and every image's camera pose in odom (odomMc: t, q as
x, y, z, w) at its capture time, with its bag stamp (capture time + latency).
"""
import bisect
import json
import statistics


def load(path):
    """The truth JSON as a dict (raises OSError or ValueError)."""
    with open(path) as f:
        return json.load(f)


def rot(q):
    """The rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def apply(R, v):
    return [sum(R[i][j] * v[j] for j in range(3)) for i in range(3)]


def apply_transposed(R, v):
    return [sum(R[j][i] * v[j] for j in range(3)) for i in range(3)]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def wall_distance(truth, odom_P):
    """|n.P - d|: a point in odom to the truth wall, m."""
    n, d = truth["wall"]["n"], truth["wall"]["d"]
    return abs(dot(n, odom_P) - d)


def camera_point_errors(truth, image, c_P, sigma):
    """A point in image's camera (camera_optical at its capture) against the wall: a dict with dist
    (|distance to the wall|, m), rel (|zc - z_true| / z_true along the point's ray), rel_sigma
    (sigma / zc), err_sigma (|zc - z_true| / sigma) and within (|zc - z_true| <= 3 sigma)."""
    n, d = truth["wall"]["n"], truth["wall"]["d"]
    R, t = rot(image["q"]), image["t"]
    zc = c_P[2]
    odom_P = [p + q for p, q in zip(apply(R, c_P), t)]
    ray = apply(R, [c_P[0] / zc, c_P[1] / zc, 1.0])  # the pixel's ray, camera z = 1, in odom
    z_true = (d - dot(n, t)) / dot(n, ray)
    err = abs(zc - z_true)
    return {"dist": abs(dot(n, odom_P) - d), "rel": err / z_true, "rel_sigma": sigma / zc,
            "err_sigma": err / sigma if sigma > 0 else float("inf"), "within": err <= 3 * sigma}


def odom_to_camera(image, odom_P):
    """A point in odom into image's truth camera: R^T (P - t)."""
    R, t = rot(image["q"]), image["t"]
    return apply_transposed(R, [p - q for p, q in zip(odom_P, t)])


def image_by_stamp(truth, tolerance=1e-6):
    """A function stamp (s, float) -> the truth image with that stamp (within tolerance s: the JSON's
    decimal and the ROS sec/nsec stamp of the same double), or None."""
    images = sorted(truth["images"], key=lambda im: im["stamp"])
    stamps = [im["stamp"] for im in images]

    def find(stamp):
        i = bisect.bisect_left(stamps, stamp - tolerance)
        if i < len(stamps) and abs(stamps[i] - stamp) <= tolerance:
            return images[i]
        return None
    return find


def summary(errors):
    """errors: camera_point_errors dicts. (N, median dist m, median rel, within fraction, median
    rel_sigma, median err_sigma), or None when empty."""
    if not errors:
        return None
    return (len(errors), statistics.median(e["dist"] for e in errors), statistics.median(e["rel"] for e in errors),
            sum(e["within"] for e in errors) / len(errors), statistics.median(e["rel_sigma"] for e in errors),
            statistics.median(e["err_sigma"] for e in errors))
