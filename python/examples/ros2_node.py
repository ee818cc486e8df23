"""A ROS 2 node sketch: aligned colour and depth in, the rope's nodes out.

UNTESTED: ROS 2 cannot be installed on the machines this project is built
on. It shows the shape of the glue (message conversion, one Tracker per
camera) for a roboticist to adapt; the tracking itself is the package's.

Subscribes to `color` (sensor_msgs/Image, rgb8 or bgr8), `depth`
(sensor_msgs/Image, 16UC1, aligned to colour, e.g. realsense-ros with
align_depth.enable:=true) and `camera_info` (sensor_msgs/CameraInfo);
publishes `rope/nodes` (sensor_msgs/PointCloud2, x y z float32, in the
colour camera's frame).
"""

import numpy as np
import rclpy
from message_filters import ApproximateTimeSynchronizer, Subscriber
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, Image, PointCloud2, PointField

import upetrack


class RopeTracker(Node):
    def __init__(self):
        super().__init__("upetrack")
        self.tracker = None
        self.create_subscription(CameraInfo, "camera_info", self.on_info, 1)
        sync = ApproximateTimeSynchronizer([Subscriber(self, Image, "color"), Subscriber(self, Image, "depth")], 5, 0.02)
        sync.registerCallback(self.on_frames)
        self.publisher = self.create_publisher(PointCloud2, "rope/nodes", 1)

    def on_info(self, info):
        if self.tracker is None:
            k = info.k
            intrinsics = upetrack.Intrinsics(info.width, info.height, k[0], k[4], k[2], k[5])
            self.tracker = upetrack.Tracker(intrinsics, depth_scale=0.001)

    def on_frames(self, color_msg, depth_msg):
        if self.tracker is None:
            return
        color = np.frombuffer(color_msg.data, np.uint8).reshape(color_msg.height, color_msg.width, 3)
        if color_msg.encoding == "bgr8":
            color = color[:, :, ::-1]
        depth = np.frombuffer(depth_msg.data, np.uint16).reshape(depth_msg.height, depth_msg.width)
        result = self.tracker.step(np.ascontiguousarray(color), np.ascontiguousarray(depth))
        points = result.nodes.astype(np.float32)
        cloud = PointCloud2()
        cloud.header = color_msg.header
        cloud.height, cloud.width = 1, len(points)
        cloud.fields = [PointField(name=n, offset=4 * i, datatype=PointField.FLOAT32, count=1) for i, n in enumerate("xyz")]
        cloud.point_step, cloud.row_step = 12, 12 * len(points)
        cloud.is_dense = True
        cloud.data = points.tobytes()
        self.publisher.publish(cloud)


def main():
    rclpy.init()
    rclpy.spin(RopeTracker())


if __name__ == "__main__":
    main()
