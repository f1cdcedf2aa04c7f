#!/usr/bin/python3
"""Writes a large ROS 1 bag with real rosbag (Debian's python3-rosbag) for bench_import_bag.sh: a
robot's recording as a camera driver and odometry write it. /camera/image_raw mono8 640x480 at
30 Hz (windows of a real photograph, ViSP's Solvay image, sliding 2 px per frame, so that PNG
encoding meets real content), /camera/camera_info at 30 Hz, /odom at 100 Hz, /tf_static once.
usage: write_large_bag.py OUT.bag SIZE_MB
       write_large_bag.py --raw OUT.raw   (the photo's gray pixels, for write_large_mcap.mjs; prints W H)"""
import math
import sys

import cv2
import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image
from tf2_msgs.msg import TFMessage

photo = cv2.imread('/usr/share/visp-images-data/ViSP-images/Solvay/Solvay_conference_1927_Version2_1280x881.jpg',
                   cv2.IMREAD_GRAYSCALE)
if photo is None:
    sys.exit('write_large_bag.py: the Solvay photo of visp-images-data is missing')
if sys.argv[1] == '--raw':  # the photo's gray pixels for write_large_mcap.mjs, and its size
    open(sys.argv[2], 'wb').write(photo.tobytes())
    print(photo.shape[1], photo.shape[0])
    sys.exit(0)
out, size_mb = sys.argv[1], float(sys.argv[2])
W, H, T0 = 640, 480, 1700000000.0


def stamp(t):
    ns = int(round(t * 1e9))
    return rospy.Time(ns // 1000000000, ns % 1000000000)


info = CameraInfo()
info.header.frame_id = 'camera_optical_frame'
info.width, info.height, info.distortion_model = W, H, 'plumb_bob'
info.D = [0.0] * 5
info.K = [500.0, 0, 320, 0, 500.0, 240, 0, 0, 1]
info.R = [1.0, 0, 0, 0, 1, 0, 0, 0, 1]
info.P = [500.0, 0, 320, 0, 0, 500.0, 240, 0, 0, 0, 1, 0]
mount = TransformStamped()
mount.header.stamp, mount.header.frame_id, mount.child_frame_id = stamp(T0), 'base_link', 'camera_optical_frame'
mount.transform.translation.x = 0.1
mount.transform.rotation.x, mount.transform.rotation.y, mount.transform.rotation.z, mount.transform.rotation.w = \
    -0.5, 0.5, -0.5, 0.5  # REP 103: the optical frame's z along base_link's x
frame_bytes = W * H
frames = int(size_mb * 1e6 / (frame_bytes + 400))
with rosbag.Bag(out, 'w') as bag:
    bag.write('/tf_static', TFMessage([mount]), stamp(T0))
    for k in range(int(frames * 100 / 30) + 10):  # odometry over the images' span and a little more
        t = T0 + k / 100.0
        o = Odometry()
        o.header.stamp, o.header.frame_id, o.child_frame_id = stamp(t), 'odom', 'base_link'
        o.pose.pose.position.x = 0.5 * (t - T0)
        yaw = 0.1 * (t - T0)
        o.pose.pose.orientation.z, o.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        bag.write('/odom', o, stamp(t))
    for k in range(frames):
        t = T0 + 0.05 + k / 30.0
        x = (2 * k) % (photo.shape[1] - W)
        img = Image()
        img.header.stamp, img.header.frame_id = stamp(t), 'camera_optical_frame'
        img.height, img.width, img.encoding, img.step = H, W, 'mono8', W
        img.data = photo[200:200 + H, x:x + W].tobytes()
        bag.write('/camera/image_raw', img, stamp(t))
        info.header.stamp = stamp(t)
        bag.write('/camera/camera_info', info, stamp(t))
print(frames, frames / 30.0)
