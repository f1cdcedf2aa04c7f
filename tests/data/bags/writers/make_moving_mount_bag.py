#!/usr/bin/python3
"""Writes tests/data/bags/moving_mount.bag with real rosbag (Debian's python3-rosbag): a REP 103
robot whose pan joint robot_state_publisher publishes on /tf, so that the camera's mount moves.

    /usr/bin/python3 tests/data/bags/writers/make_moving_mount_bag.py tests/data/bags

Times from T0 = 1700000000 s, tau = t - T0; the formulas are test_bag_ros1's:
  /odom          odom -> base_link at 100 Hz over tau in [0, 1]: position (0.5 tau, 0.1 sin tau, 0),
                 a turn of 0.3 tau about z
  /tf            base_link -> pan_link at 50 Hz over tau in [0, 1]: translation (0.1, 0, 0.4), a turn
                 of 0.4 sin(pi tau) about z (the pan joint)
  /tf_static     pan_link -> camera_optical_frame: translation (0.05, 0, 0.05), REP 103's optical
                 rotation (x, y, z, w) = (-0.5, 0.5, -0.5, 0.5)
  /joint_states  pan_joint at 50 Hz (the same angle)
  /camera/image_raw, /camera/camera_info  mono8 16x12 at 20 Hz, stamps T0 + 0.025 + 0.05 k, k = 0..19
"""
import math
import os
import sys

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, JointState
from tf2_msgs.msg import TFMessage

T0 = 1700000000.0


def rt(t):
    ns = int(round(t * 1e9))
    return rospy.Time(ns // 1000000000, ns % 1000000000)


def zturn(a):
    return [0.0, 0.0, math.sin(a / 2), math.cos(a / 2)]


def transform(t, parent, child, p, q):
    x = TransformStamped()
    x.header.stamp, x.header.frame_id, x.child_frame_id = rt(t), parent, child
    x.transform.translation.x, x.transform.translation.y, x.transform.translation.z = p
    x.transform.rotation.x, x.transform.rotation.y, x.transform.rotation.z, x.transform.rotation.w = q
    return x


out = os.path.join(sys.argv[1], 'moving_mount.bag')
with rosbag.Bag(out, 'w') as bag:
    bag.write('/tf_static', TFMessage([transform(T0, 'pan_link', 'camera_optical_frame', (0.05, 0, 0.05),
                                                 (-0.5, 0.5, -0.5, 0.5))]), rt(T0))
    for k in range(101):
        tau = k / 100.0
        o = Odometry()
        o.header.stamp, o.header.frame_id, o.child_frame_id = rt(T0 + tau), 'odom', 'base_link'
        o.pose.pose.position.x, o.pose.pose.position.y = 0.5 * tau, 0.1 * math.sin(tau)
        q = zturn(0.3 * tau)
        o.pose.pose.orientation.x, o.pose.pose.orientation.y, o.pose.pose.orientation.z, o.pose.pose.orientation.w = q
        bag.write('/odom', o, rt(T0 + tau))
    for k in range(51):
        tau = k / 50.0
        pan = 0.4 * math.sin(math.pi * tau)
        bag.write('/tf', TFMessage([transform(T0 + tau, 'base_link', 'pan_link', (0.1, 0, 0.4), zturn(pan))]),
                  rt(T0 + tau))
        j = JointState()
        j.header.stamp = rt(T0 + tau)
        j.name, j.position = ['pan_joint'], [pan]
        bag.write('/joint_states', j, rt(T0 + tau))
    for k in range(20):
        t = T0 + 0.025 + 0.05 * k
        img = Image()
        img.header.stamp, img.header.frame_id = rt(t), 'camera_optical_frame'
        img.height, img.width, img.encoding, img.step = 12, 16, 'mono8', 16
        img.data = bytes((7 * k + i) % 256 for i in range(16 * 12))
        bag.write('/camera/image_raw', img, rt(t))
        info = CameraInfo()
        info.header = img.header
        info.height, info.width, info.distortion_model = 12, 16, 'plumb_bob'
        info.D = [0.0] * 5
        info.K = [20.0, 0, 8, 0, 20.0, 6, 0, 0, 1]
        info.R = [1.0, 0, 0, 0, 1, 0, 0, 0, 1]
        info.P = [20.0, 0, 8, 0, 0, 20.0, 6, 0, 0, 0, 1, 0]
        bag.write('/camera/camera_info', info, rt(t))
