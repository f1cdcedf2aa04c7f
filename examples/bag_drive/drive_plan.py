#!/usr/bin/python3
"""The messages of the drive's bags, computed once from `yawdepth simulate`'s output, for both writers
(write_ros1_bag.py and write_mcap.mjs), so that the ROS 1 and ROS 2 bags hold the same values.

    drive_plan.py SIM_DIR CAMERA_XML RIG_YAML OUT_DIR

Reads SIM_DIR/motion.csv (the dead-reckoned odometry with its pan readings and images),
SIM_DIR/motion_truth.csv (the true poses) and the images; writes
    OUT_DIR/plan.json    every message's values (times as [sec, nanosec] pairs: JSON numbers cannot
                         hold nanoseconds since the epoch)
    OUT_DIR/pixels/      each image's pixels, row-major mono8 (the raw Image messages' data)
    OUT_DIR/stamps.csv   frame,exposure_ns,stamp_ns,image: which rendered frame each image stamp is

Frames (all right-handed):
  odom                  the world of the motion log, yawdepth's camera convention: x right, y down,
                        z forward of the robot at its start (NOT REP 103's x forward, z up).
  base_link             yawdepth's vision frame: on the robot at the pan axis, axes as odom's at
                        heading 0 (x right, y down, z forward). The pan joint turns about its +y.
  pan_link              the pan joint's child at yaw 0: coincides with base_link.
  camera_optical_frame  the camera (x right, y down, z along the optical axis), at the rig's
                        camera_offset in pan_link, axes parallel to pan_link's.
A planar motion row (x, y, z, heading) is the pose odom -> base_link: position (x, y, z), rotation
R_y(heading), i.e. the quaternion (0, sin(h/2), 0, cos(h/2)).

Times: the images are exposed at T0 + k / 20 Hz (frame k of the rendering); their header stamps are
LATENCY = 40 ms later (a camera driver that stamps on arrival), so the import needs --time-offset -0.04
(the image stamped t was taken at odometry time t - 0.04). Odometry and /tf at 100 Hz, /joint_states at
50 Hz, both stamped on the exposure clock, from 0.2 s before the first image to 0.2 s after the last
exposure, linearly interpolated between the rendered frames (constant velocity beyond the ends). Since
the exposures fall on the 100 Hz grid, the odometry at each image is exactly the row of motion.csv,
and the pan is linear (simulate's --sigma-yaw 0), so the 50 Hz joint states give it back exactly too.
"""
import json
import math
import os
import re
import struct
import sys
import xml.etree.ElementTree as ET
import zlib

T0 = 1700000000  # s: the first exposure
IMAGE_HZ, ODOM_HZ, JOINT_HZ = 20, 100, 50
LATENCY_NS = 40000000
MARGIN_NS = 200000000


def read_csv(path):
    with open(path) as f:
        lines = [l.rstrip("\n") for l in f if l.strip()]
    head = lines[0].split(",")
    return [dict(zip(head, l.split(","))) for l in lines[1:]]


def png_gray(path):
    """The pixels of an 8-bit grayscale, non-interlaced PNG (what simulate writes), standard library only."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or color != 0 or interlace:
                raise SystemExit(f"{path}: not an 8-bit grayscale non-interlaced PNG")
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    raw = zlib.decompress(idat)
    out, prev = bytearray(), bytearray(w)
    for y in range(h):
        f, line = raw[y * (w + 1)], bytearray(raw[y * (w + 1) + 1:(y + 1) * (w + 1)])
        for x in range(w):
            a = line[x - 1] if x else 0
            b = prev[x]
            c = prev[x - 1] if x else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line
        prev = line
    return w, h, bytes(out)


def camera_xml(path):
    """px, py, u0, v0 and the image size of a ViSP camera XML's perspectiveProjWithoutDistortion model."""
    root = ET.parse(path).getroot()
    cam = root.find("camera")
    for model in cam.findall("model"):
        if model.findtext("type").strip() == "perspectiveProjWithoutDistortion":
            g = lambda k: float(model.findtext(k))
            return dict(width=int(cam.findtext("image_width")), height=int(cam.findtext("image_height")),
                        px=g("px"), py=g("py"), u0=g("u0"), v0=g("v0"))
    raise SystemExit(f"{path}: no perspectiveProjWithoutDistortion model")


def stamp(ns):
    return [ns // 1000000000, ns % 1000000000]


def main():
    sim, cam_path, rig_path, out = sys.argv[1:5]
    os.makedirs(os.path.join(out, "pixels"), exist_ok=True)
    rows = read_csv(os.path.join(sim, "motion.csv"))
    cam = camera_xml(cam_path)
    m = re.search(r"^camera_offset:\s*\[([^\]]*)\]", open(rig_path).read(), re.M)
    if not m:
        raise SystemExit(f"{rig_path}: no camera_offset")
    offset = [float(v) for v in m.group(1).split(",")]

    frame_ns = 1000000000 // IMAGE_HZ
    t0_ns = T0 * 1000000000
    n = len(rows)
    val = lambda r, k: float(r[k])

    def motion_at(t_ns):
        """x, y, z, heading, yaw and their rates (per s) at time t on the exposure clock."""
        f = (t_ns - t0_ns) / frame_ns
        i = min(max(int(math.floor(f)), 0), n - 2)
        s = f - i
        a, b = rows[i], rows[i + 1]
        v = [val(a, k) + s * (val(b, k) - val(a, k)) for k in ("x", "y", "z", "heading", "yaw")]
        d = [(val(b, k) - val(a, k)) * IMAGE_HZ for k in ("x", "y", "z", "heading", "yaw")]
        return v, d

    frames = []
    with open(os.path.join(out, "stamps.csv"), "w") as st:
        st.write("frame,exposure_ns,stamp_ns,image\n")
        for k, r in enumerate(rows):
            exp_ns = t0_ns + k * frame_ns
            w, h, px = png_gray(os.path.join(sim, r["image"]))
            if (w, h) != (cam["width"], cam["height"]):
                raise SystemExit(f"{r['image']}: {w}x{h}, the camera is {cam['width']}x{cam['height']}")
            gray = os.path.join("pixels", "%04d.gray" % k)
            open(os.path.join(out, gray), "wb").write(px)
            frames.append(dict(frame=int(r["frame"]), stamp=stamp(exp_ns + LATENCY_NS),
                               png=os.path.abspath(os.path.join(sim, r["image"])), gray=gray))
            st.write("%s,%d,%d,%s\n" % (r["frame"], exp_ns, exp_ns + LATENCY_NS, r["image"]))

    start, end = t0_ns - MARGIN_NS, t0_ns + (n - 1) * frame_ns + MARGIN_NS
    odom = []
    step = 1000000000 // ODOM_HZ
    for t in range(start, end + 1, step):
        (x, y, z, hd, _), (dx, dy, dz, dh, _) = motion_at(t)
        c, s = math.cos(hd), math.sin(hd)
        # The twist in base_link (child_frame_id), as nav_msgs/Odometry has it: R_y(h)^T * d(x,y,z)/dt.
        odom.append(dict(stamp=stamp(t), p=[x, y, z], q=[0.0, math.sin(hd / 2), 0.0, math.cos(hd / 2)],
                         v=[c * dx - s * dz, dy, s * dx + c * dz], w=[0.0, dh, 0.0]))
    joints = []
    step = 1000000000 // JOINT_HZ
    for t in range(start, end + 1, step):
        (_, _, _, _, yaw), (_, _, _, _, dyaw) = motion_at(t)
        joints.append(dict(stamp=stamp(t), position=yaw, velocity=dyaw))

    fx, fy, u0, v0 = cam["px"], cam["py"], cam["u0"], cam["v0"]
    plan = dict(
        t0=stamp(t0_ns),
        latency_ns=LATENCY_NS,
        camera=dict(width=cam["width"], height=cam["height"], distortion_model="plumb_bob", d=[0.0] * 5,
                    k=[fx, 0.0, u0, 0.0, fy, v0, 0.0, 0.0, 1.0], r=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                    p=[fx, 0.0, u0, 0.0, 0.0, fy, v0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        frames=frames,
        odom=odom,
        joints=joints,
        joint_name="pan_joint",
        # The yaw-0 mount only: base_link -> pan_link (the pan joint at yaw 0) -> camera_optical_frame.
        # The pan's rotation is NOT in any transform: it is in /joint_states alone. yawdepth's rig gives
        # the camera's pose in the vision frame at yaw 0 (import-bag writes it from this /tf_static
        # chain as rig.yaml's camera_pose) and the motion log's yaw column turns it about base_link's +y
        # (import-bag writes the pan_joint positions there). A robot_state_publisher would instead
        # publish base_link -> pan_link on /tf with the joint's rotation; that moving transform would
        # then be the camera's pan, which yawdepth must see as the yaw column, not in the mount.
        tf_static=[
            dict(parent="base_link", child="pan_link", t=[0.0, 0.0, 0.0], q=[0.0, 0.0, 0.0, 1.0]),
            dict(parent="pan_link", child="camera_optical_frame", t=offset, q=[0.0, 0.0, 0.0, 1.0]),
        ],
        tf_static_stamp=stamp(start - 100000000),
    )
    with open(os.path.join(out, "plan.json"), "w") as f:
        json.dump(plan, f)
    print(f"drive_plan: {n} images at {IMAGE_HZ} Hz (stamped {LATENCY_NS / 1e6:.0f} ms late), "
          f"{len(odom)} odometry poses at {ODOM_HZ} Hz, {len(joints)} joint states at {JOINT_HZ} Hz")


if __name__ == "__main__":
    main()
