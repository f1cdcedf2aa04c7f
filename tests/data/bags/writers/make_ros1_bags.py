#!/usr/bin/python3
"""Writes the ROS 1 test bags of tests/data/bags/ with real rosbag (Debian's python3-rosbag), and
ros1_truth.json, the values every message was written with. Run with Debian's python3:

    /usr/bin/python3 tests/data/bags/writers/make_ros1_bags.py tests/data/bags
    /usr/bin/python3 tests/data/bags/writers/make_ros1_bags.py --fuzz-seeds fuzz/corpus/ros1_bag

Bags (times are ROS times from T0 = 1700000000 s; tau = t - T0):
  robot.bag      uncompressed. /camera/image_raw mono8 16x12 at 20 Hz (stamps T0 - 0.03 + 0.05 k,
                 k = 0..21, logged 40 ms after their stamp) and /camera/camera_info; /odom (odom ->
                 base_link, 100 Hz, tau in [0, 0.99], none in (0.50, 0.80): a 0.3 s gap); /pose
                 (PoseStamped, world -> base_link, 50 Hz); /pose_cov (PoseWithCovarianceStamped);
                 /tf (world -> odom and odom -> base_link, 50 Hz); /tf_static (base_link -> pan_link
                 -> camera_link -> camera_optical_frame, REP 103's optical rotation); /joint_states
                 (wheel, pan_joint at 50 Hz over tau in [0.1, 0.9]).
  encodings.bag  lz4 chunks. 4 images in each of mono8, rgb8, bgr8, mono16, a JPEG and a PNG
                 CompressedImage (/cam/NAME/image_raw[/compressed]), one /cam/camera_info for them
                 all; /odom at 50 Hz over tau in [0, 0.4].
  camera_cases.bag  lz4. /cam/image_raw (mono8 16x12) with four camera_info topics: /cam/camera_info
                 (K changes at the third), /cam/fisheye_xyz_info (an unknown distortion model),
                 /cam/big_info (20x15), /cam/equidistant_info; /odom, /tf_static.
  measure.bag    lz4. /camera/image_raw/compressed (PNG, 320x240, a 9x6 chessboard of 0.04 m squares
                 rendered through the camera), /camera/camera_info, /odom 100 Hz, /tf_static; the
                 board's plane and corners in the world in the truth.
"""
import json
import math
import os
import sys

import cv2
import numpy as np
import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, CompressedImage, Image, JointState
from tf2_msgs.msg import TFMessage

T0 = 1700000000.0


def rt(t):
    ns = int(round(t * 1e9))
    return rospy.Time(ns // 1000000000, ns % 1000000000)


def quat_rpy(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return [sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy]


def odom_pose(tau):
    """base_link in odom: position and quaternion (x, y, z, w)."""
    p = [0.5 * tau, 0.1 * math.sin(2 * tau), 0.0]
    q = quat_rpy(0.02 * math.sin(5 * tau), 0.0, 0.3 * tau + 0.1 * math.sin(3 * tau))
    return p, q


def world_odom(tau):
    """odom in world: a slow drift."""
    return [1.0 + 0.02 * tau, 2.0, 0.1], quat_rpy(0.0, 0.0, 0.1)


def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz]


def qrot(q, v):
    x, y, z, w = q
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    return r @ np.asarray(v)


def compose(a, b):
    (pa, qa), (pb, qb) = a, b
    return list(np.asarray(pa) + qrot(qa, pb)), qmul(qa, qb)


def world_body(tau):
    return compose(world_odom(tau), odom_pose(tau))


def header(msg, t, frame):
    msg.header.stamp = rt(t)
    msg.header.frame_id = frame


def transform(t, parent, child, p, q):
    m = TransformStamped()
    header(m, t, parent)
    m.child_frame_id = child
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = p
    (m.transform.rotation.x, m.transform.rotation.y, m.transform.rotation.z, m.transform.rotation.w) = q
    return m


def set_pose(pose, p, q):
    pose.position.x, pose.position.y, pose.position.z = p
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = q


OPTICAL = [-0.5, 0.5, -0.5, 0.5]  # REP 103: z forward, x right, y down in a body-like (x forward, z up) link
STATIC = [("base_link", "pan_link", [0.1, 0.0, 0.3], [0, 0, 0, 1]),
          ("pan_link", "camera_link", [0.05, 0.01, 0.02], quat_rpy(0.0, 0.05, 0.0)),
          ("camera_link", "camera_optical_frame", [0.0, 0.0, 0.0], OPTICAL)]


def camera_info(t, frame, w, h, fx, model="plumb_bob", D=None):
    c = CameraInfo()
    header(c, t, frame)
    c.width, c.height = w, h
    c.distortion_model = model
    c.D = list(D if D is not None else [0.01, -0.002, 0.0005, -0.0003, 0.0001])
    cx, cy = (w - 1) / 2.0, (h - 1) / 2.0
    c.K = [fx, 0, cx, 0, fx * 1.01, cy, 0, 0, 1]
    c.R = [1, 0, 0, 0, 1, 0, 0, 0, 1]
    c.P = [fx, 0, cx, 0, 0, fx * 1.01, cy, 0, 0, 0, 1, 0]
    return c


def info_json(c):
    return {"stamp_ns": c.header.stamp.to_nsec(), "frame_id": c.header.frame_id, "width": c.width,
            "height": c.height, "distortion_model": c.distortion_model, "D": list(c.D), "K": list(c.K),
            "R": list(c.R), "P": list(c.P)}


def pattern(k, w, h, channels=1, dtype=np.uint8):
    """A small image that differs per frame: a gradient plus the frame number."""
    yy, xx = np.mgrid[0:h, 0:w]
    img = np.zeros((h, w, channels), dtype=np.int64)
    for c in range(channels):
        img[:, :, c] = (xx * 13 + yy * 7 + 40 * c + 9 * k) % 256
    if dtype == np.uint16:
        img = img * 257 + 3
    return img.astype(dtype).reshape((h, w) if channels == 1 else (h, w, channels))


def raw_image(t, frame, arr, encoding):
    m = Image()
    header(m, t, frame)
    m.height, m.width = arr.shape[0], arr.shape[1]
    m.encoding = encoding
    m.is_bigendian = 0
    m.step = arr.shape[1] * (arr.shape[2] if arr.ndim == 3 else 1) * arr.dtype.itemsize
    m.data = arr.astype(arr.dtype.newbyteorder('<')).tobytes()
    return m


def write_odom(bag, taus, truth_list, frame="odom", child="base_link"):
    for tau in taus:
        t = T0 + tau
        o = Odometry()
        header(o, t, frame)
        o.child_frame_id = child
        p, q = odom_pose(tau)
        set_pose(o.pose.pose, p, q)
        o.pose.covariance = [0.001 * (i + 1) if i % 7 == 0 else 0.0 for i in range(36)]
        o.twist.twist.linear.x = 0.5
        bag.write("/odom", o, rt(t + 0.002))
        truth_list.append({"stamp_ns": o.header.stamp.to_nsec(), "position": p, "orientation": q})


def robot_bag(out, truth):
    bag = rosbag.Bag(os.path.join(out, "robot.bag"), "w")
    static = TFMessage([transform(T0, a, b, p, q) for a, b, p, q in STATIC])
    bag.write("/tf_static", static, rt(T0))
    truth["static"] = [{"parent": a, "child": b, "translation": p, "rotation": q} for a, b, p, q in STATIC]
    events = []
    images, infos = [], []
    for k in range(22):
        t = T0 - 0.03 + 0.05 * k
        img = raw_image(t, "camera_optical_frame", pattern(k, 16, 12), "mono8")
        events.append((t + 0.040, "/camera/image_raw", img))
        c = camera_info(t, "camera_optical_frame", 16, 12, 20.0)
        events.append((t + 0.040, "/camera/camera_info", c))
        images.append({"stamp_ns": img.header.stamp.to_nsec(), "log_ns": rt(t + 0.040).to_nsec(),
                       "frame_id": img.header.frame_id, "width": 16, "height": 12, "encoding": "mono8",
                       "step": img.step, "first_bytes": list(bytearray(img.data[:8]))})
        infos.append(info_json(c))
    truth["images"] = images
    truth["camera_info"] = infos[0]
    odom = []
    taus = [i / 100.0 for i in range(100) if not (50 < i < 80)]
    # Odometry, poses, /tf, joints, in log-time order by rosbag's index (any write order).
    write_odom(bag, taus, odom)
    truth["odom"] = odom
    poses = []
    for i in range(50):
        tau = i / 50.0
        t = T0 + tau
        p, q = world_body(tau)
        ps = PoseStamped()
        header(ps, t, "world")
        set_pose(ps.pose, p, q)
        events.append((t + 0.001, "/pose", ps))
        pc = PoseWithCovarianceStamped()
        header(pc, t, "world")
        set_pose(pc.pose.pose, p, q)
        pc.pose.covariance = [0.01 if i2 % 7 == 0 else 0.0 for i2 in range(36)]
        events.append((t + 0.001, "/pose_cov", pc))
        poses.append({"stamp_ns": ps.header.stamp.to_nsec(), "position": [float(x) for x in p], "orientation": q})
        wo = world_odom(tau)
        ob = odom_pose(tau)
        events.append((t + 0.003, "/tf", TFMessage([transform(t, "world", "odom", *wo),
                                                     transform(t, "odom", "base_link", *ob)])))
    truth["pose"] = poses
    joints = []
    for i in range(41):
        tau = 0.1 + i / 50.0
        t = T0 + tau
        j = JointState()
        header(j, t, "")
        j.name = ["wheel", "pan_joint"]
        pan = 0.2 * math.sin(2 * math.pi * 0.5 * tau)
        j.position = [3.0 * tau, pan]
        j.velocity = [3.0, 0.2 * math.pi * math.cos(math.pi * tau)]
        j.effort = []
        events.append((t + 0.001, "/joint_states", j))
        joints.append({"stamp_ns": j.header.stamp.to_nsec(), "name": j.name, "position": j.position,
                       "velocity": j.velocity})
    truth["joint_states"] = joints
    for t, topic, msg in sorted(events, key=lambda e: e[0]):
        bag.write(topic, msg, rt(t))
    bag.close()


def encodings_bag(out, truth):
    bag = rosbag.Bag(os.path.join(out, "encodings.bag"), "w", compression="lz4")
    bag.write("/tf_static", TFMessage([transform(T0, a, b, p, q) for a, b, p, q in STATIC]), rt(T0))
    odom = []
    write_odom(bag, [i / 50.0 for i in range(21)], odom)
    for k in range(4):  # one camera_info for every encoding's topic
        t = T0 + 0.05 + 0.1 * k
        bag.write("/cam/camera_info", camera_info(t, "camera_optical_frame", 16, 12, 20.0), rt(t + 0.01))
    enc = {}
    for k in range(4):
        t = T0 + 0.05 + 0.1 * k
        for name, arr, encoding in [("mono8", pattern(k, 16, 12), "mono8"),
                                    ("rgb8", pattern(k, 16, 12, 3), "rgb8"),
                                    ("bgr8", pattern(k, 16, 12, 3), "bgr8"),
                                    ("mono16", pattern(k, 16, 12, 1, np.uint16), "mono16")]:
            m = raw_image(t, "camera_optical_frame", arr, encoding)
            bag.write("/cam/%s/image_raw" % name, m, rt(t + 0.01))
            enc.setdefault(name, []).append({"stamp_ns": m.header.stamp.to_nsec(), "encoding": encoding,
                                             "step": m.step, "first_bytes": list(bytearray(m.data[:8]))})
        for name, ext in [("jpeg", ".jpg"), ("png", ".png")]:
            bgr = pattern(k, 16, 12, 3)
            ok, data = cv2.imencode(ext, bgr)
            assert ok
            m = CompressedImage()
            header(m, t, "camera_optical_frame")
            m.format = name
            m.data = data.tobytes()
            bag.write("/cam/%s/image_raw/compressed" % name, m, rt(t + 0.01))
            enc.setdefault(name, []).append({"stamp_ns": m.header.stamp.to_nsec(), "bytes": len(m.data),
                                             "first_bytes": list(bytearray(m.data[:8]))})
    truth["encodings"] = enc
    bag.close()


def camera_cases_bag(out, truth):
    bag = rosbag.Bag(os.path.join(out, "camera_cases.bag"), "w", compression="lz4")
    odom = []
    write_odom(bag, [i / 50.0 for i in range(16)], odom)
    bag.write("/tf_static", TFMessage([transform(T0, a, b, p, q) for a, b, p, q in STATIC]), rt(T0))
    for k in range(3):
        t = T0 + 0.05 + 0.1 * k
        bag.write("/cam/image_raw", raw_image(t, "camera_optical_frame", pattern(k, 16, 12), "mono8"), rt(t + 0.01))
        bag.write("/cam/camera_info", camera_info(t, "camera_optical_frame", 16, 12, 20.0 + 2.0 * (k == 2)), rt(t + 0.01))
        bag.write("/cam/fisheye_xyz_info", camera_info(t, "camera_optical_frame", 16, 12, 20.0, "fisheye_xyz"),
                  rt(t + 0.01))
        bag.write("/cam/big_info", camera_info(t, "camera_optical_frame", 20, 15, 20.0), rt(t + 0.01))
        bag.write("/cam/equidistant_info", camera_info(t, "camera_optical_frame", 16, 12, 20.0, "equidistant",
                                                       [0.01, -0.002, 0.0005, -0.0001]), rt(t + 0.01))
    bag.close()


def render_board(wMc, K, w, h, board):
    """The chessboard seen by a camera at wMc (p, q): 2x2 supersampled, 8-bit gray."""
    (pc, qc) = wMc
    x0, y_left, z_top, sq, cols, rows = board
    ss = 2
    vv, uu = np.mgrid[0:h * ss, 0:w * ss]
    u = (uu + 0.5) / ss - 0.5
    v = (vv + 0.5) / ss - 0.5
    d = np.stack([(u - K[2]) / K[0], (v - K[5]) / K[4], np.ones_like(u)], axis=-1)
    x, y, z, ww = qc
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * ww), 2 * (x * z + y * ww)],
                  [2 * (x * y + z * ww), 1 - 2 * (x * x + z * z), 2 * (y * z - x * ww)],
                  [2 * (x * z - y * ww), 2 * (y * z + x * ww), 1 - 2 * (x * x + y * y)]])
    dw = d @ R.T
    s = (x0 - pc[0]) / dw[..., 0]
    py = pc[1] + s * dw[..., 1]
    pz = pc[2] + s * dw[..., 2]
    a = (y_left - py) / sq  # along the rows, to the right
    b = (z_top - pz) / sq   # down
    img = np.full(a.shape, 150.0)
    inside = (a >= -1) & (a < cols + 2) & (b >= -1) & (b < rows + 2)
    img[inside] = 255.0
    board_area = (a >= 0) & (a < cols + 1) & (b >= 0) & (b < rows + 1)
    dark = ((np.floor(a).astype(int) + np.floor(b).astype(int)) % 2 == 0) & board_area
    img[dark] = 20.0
    img = img.reshape(h, ss, w, ss).mean(axis=(1, 3))
    return np.clip(img + 0.5, 0, 255).astype(np.uint8)


def measure_bag(out, truth):
    bag = rosbag.Bag(os.path.join(out, "measure.bag"), "w", compression="lz4")
    bag.write("/tf_static", TFMessage([transform(T0, a, b, p, q) for a, b, p, q in STATIC]), rt(T0))
    w, h, f = 320, 240, 300.0

    def body(tau):  # base_link in odom: sideways to the left, slowly turning
        return [0.0, 0.3 * tau, 0.0], quat_rpy(0.0, 0.0, 0.05 * tau)

    for i in range(101):
        tau = i / 100.0
        o = Odometry()
        header(o, T0 + tau, "odom")
        o.child_frame_id = "base_link"
        set_pose(o.pose.pose, *body(tau))
        bag.write("/odom", o, rt(T0 + tau + 0.002))
    bMc = ([0.0, 0.0, 0.0], [0, 0, 0, 1])
    for a, b, p, q in STATIC:
        bMc = compose(bMc, (p, q))
    # The board: in the plane x = 1.45 of odom, 10 x 7 squares of 0.04 m (9 x 6 inner corners).
    sq, cols, rows = 0.04, 9, 6
    board = (1.45, 0.15 + 0.2, 0.32 + 0.14, sq, cols, rows)
    corners = [[board[0], board[1] - sq * (c + 1), board[2] - sq * (r + 1)] for r in range(rows) for c in range(cols)]
    truth["measure"] = {"board_x": board[0], "corners": corners, "square": sq}
    for k in range(10):
        tau = 0.05 + 0.1 * k
        t = T0 + tau
        wMc = compose(body(tau), bMc)
        c = camera_info(t, "camera_optical_frame", w, h, f, D=[0, 0, 0, 0, 0])
        img = render_board(wMc, c.K, w, h, board)
        ok, data = cv2.imencode(".png", img)
        assert ok
        m = CompressedImage()
        header(m, t, "camera_optical_frame")
        m.format = "png"
        m.data = data.tobytes()
        bag.write("/camera/image_raw/compressed", m, rt(t + 0.04))
        bag.write("/camera/camera_info", c, rt(t + 0.04))
    bag.close()


def fuzz_seeds(out):
    """Tiny bags for fuzz/corpus/ros1_bag: a few messages each, uncompressed and lz4, bz2."""
    os.makedirs(out, exist_ok=True)
    for name, compression, topics in [("odom_image", "none", ("odom", "image", "info")),
                                      ("tf_lz4", "lz4", ("tf", "joint")),
                                      ("info_bz2", "bz2", ("info", "pose"))]:
        bag = rosbag.Bag(os.path.join(out, name + ".bag"), "w", compression=compression)
        for k in range(2):
            t = T0 + 0.1 * k
            if "odom" in topics:
                write_odom(bag, [0.1 * k], [])
            if "image" in topics:
                bag.write("/cam/image_raw", raw_image(t, "cam", pattern(k, 4, 3), "mono8"), rt(t))
            if "tf" in topics:
                bag.write("/tf", TFMessage([transform(t, "world", "base_link", *odom_pose(0.1 * k))]), rt(t))
            if "joint" in topics:
                j = JointState()
                header(j, t, "")
                j.name, j.position = ["pan_joint"], [0.1 * k]
                bag.write("/joint_states", j, rt(t))
            if "info" in topics:
                bag.write("/cam/camera_info", camera_info(t, "cam", 4, 3, 5.0), rt(t))
            if "pose" in topics:
                ps = PoseStamped()
                header(ps, t, "world")
                set_pose(ps.pose, *odom_pose(0.1 * k))
                bag.write("/pose", ps, rt(t))
        bag.close()


def main():
    if len(sys.argv) > 2 and sys.argv[1] == "--fuzz-seeds":
        fuzz_seeds(sys.argv[2])
        return
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    truth = {"T0": T0, "image_latency": 0.040, "static_tf": [[a, b, p, q] for a, b, p, q in STATIC]}
    robot_bag(out, truth)
    encodings_bag(out, truth)
    camera_cases_bag(out, truth)
    measure_bag(out, truth)
    with open(os.path.join(out, "ros1_truth.json"), "w") as f:
        json.dump(truth, f, indent=None, separators=(",", ":"))


if __name__ == "__main__":
    main()
