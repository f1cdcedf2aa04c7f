#!/usr/bin/python3
"""The drive as a ROS 1 bag, written by ROS's own rosbag Python library (Debian's python3-rosbag with
the message modules of python3-sensor-msgs, -nav-msgs, -geometry-msgs, -tf2-msgs): run it with
Debian's /usr/bin/python3.

    write_ros1_bag.py PLAN_DIR OUT.bag

PLAN_DIR is drive_plan.py's output (plan.json, pixels/). Topics (frames: see drive_plan.py):
    /camera/image_raw             sensor_msgs/Image mono8, 20 Hz, stamped 40 ms after the exposure
    /camera/image_raw/compressed  sensor_msgs/CompressedImage, the same images as PNG
    /camera/camera_info           sensor_msgs/CameraInfo with each image (plumb_bob, all zero)
    /odom                         nav_msgs/Odometry odom -> base_link, 100 Hz
    /tf                           tf2_msgs/TFMessage odom -> base_link, 100 Hz (for --tf odom:base_link)
    /joint_states                 sensor_msgs/JointState pan_joint, 50 Hz
    /tf_static                    tf2_msgs/TFMessage base_link -> pan_link -> camera_optical_frame
                                  (the yaw-0 mount; latched, once)
Each message is logged at its stamp plus a transport delay (images 5 ms, the others 1 ms), as
`rosbag record` logs the time it received it; /tf_static at the start.
"""
import json
import os
import sys

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, CompressedImage, Image, JointState
from tf2_msgs.msg import TFMessage


def rtime(st, delay_ns=0):
    return rospy.Time(st[0], st[1]) + rospy.Duration(0, delay_ns)


def main():
    plan_dir, out = sys.argv[1], sys.argv[2]
    plan = json.load(open(os.path.join(plan_dir, "plan.json")))
    cam = plan["camera"]
    msgs = []  # (log time, topic, message, connection header)

    tf = TFMessage()
    for s in plan["tf_static"]:
        x = TransformStamped()
        x.header.stamp = rtime(plan["tf_static_stamp"])
        x.header.frame_id = s["parent"]
        x.child_frame_id = s["child"]
        x.transform.translation.x, x.transform.translation.y, x.transform.translation.z = s["t"]
        (x.transform.rotation.x, x.transform.rotation.y, x.transform.rotation.z, x.transform.rotation.w) = s["q"]
        tf.transforms.append(x)
    latched = {"latching": "1", "callerid": "/robot_state_publisher"}
    msgs.append((rtime(plan["tf_static_stamp"]), "/tf_static", tf, latched))

    for i, f in enumerate(plan["frames"]):
        st = rtime(f["stamp"])
        img = Image()
        img.header.seq, img.header.stamp, img.header.frame_id = i, st, "camera_optical_frame"
        img.height, img.width, img.encoding, img.is_bigendian = cam["height"], cam["width"], "mono8", 0
        img.step = cam["width"]
        img.data = open(os.path.join(plan_dir, f["gray"]), "rb").read()
        msgs.append((rtime(f["stamp"], 5000000), "/camera/image_raw", img, None))
        comp = CompressedImage()
        comp.header = img.header
        comp.format = "mono8; png compressed "  # image_transport's compressed format string
        comp.data = open(f["png"], "rb").read()
        msgs.append((rtime(f["stamp"], 5000000), "/camera/image_raw/compressed", comp, None))
        info = CameraInfo()
        info.header = img.header
        info.height, info.width = cam["height"], cam["width"]
        info.distortion_model = cam["distortion_model"]
        info.D, info.K, info.R, info.P = cam["d"], cam["k"], cam["r"], cam["p"]
        msgs.append((rtime(f["stamp"], 1000000), "/camera/camera_info", info, None))

    for i, o in enumerate(plan["odom"]):
        od = Odometry()
        od.header.seq, od.header.stamp, od.header.frame_id = i, rtime(o["stamp"]), "odom"
        od.child_frame_id = "base_link"
        p, q = od.pose.pose.position, od.pose.pose.orientation
        p.x, p.y, p.z = o["p"]
        q.x, q.y, q.z, q.w = o["q"]
        od.pose.covariance = [1e-8 if r == c else 0.0 for r in range(6) for c in range(6)]
        v, w = od.twist.twist.linear, od.twist.twist.angular
        v.x, v.y, v.z = o["v"]
        w.x, w.y, w.z = o["w"]
        od.twist.covariance = [1e-6 if r == c else 0.0 for r in range(6) for c in range(6)]
        msgs.append((rtime(o["stamp"], 1000000), "/odom", od, None))
        x = TransformStamped()
        x.header = od.header
        x.child_frame_id = "base_link"
        x.transform.translation.x, x.transform.translation.y, x.transform.translation.z = o["p"]
        (x.transform.rotation.x, x.transform.rotation.y, x.transform.rotation.z, x.transform.rotation.w) = o["q"]
        msgs.append((rtime(o["stamp"], 1000000), "/tf", TFMessage(transforms=[x]), None))

    for i, j in enumerate(plan["joints"]):
        js = JointState()
        js.header.seq, js.header.stamp = i, rtime(j["stamp"])
        js.name, js.position, js.velocity, js.effort = [plan["joint_name"]], [j["position"]], [j["velocity"]], [0.0]
        msgs.append((rtime(j["stamp"], 1000000), "/joint_states", js, None))

    msgs.sort(key=lambda m: m[0])
    with rosbag.Bag(out, "w") as bag:
        for t, topic, msg, header in msgs:
            if header:
                h = dict(header, topic=topic, type=msg._type, md5sum=msg._md5sum, message_definition=msg._full_text)
                bag.write(topic, msg, t, connection_header=h)
            else:
                bag.write(topic, msg, t)
    print(f"write_ros1_bag: {out}: {len(msgs)} messages")


if __name__ == "__main__":
    main()
