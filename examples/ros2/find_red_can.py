"""Find the red can with robot_000's RGB-D head camera and report where it is (plain rclpy and numpy).

The robot turns in place (cmd_vel) until a red thing appears in the colour image (the biggest one, when there are
several) and its centre is in the middle columns, stops, then reads the depth image of the same step: the median
depth of the red pixels and the camera's intrinsics (CameraInfo's K) give the can's position in the camera's optical
frame (z forward, x right, y down).

Start the world first:  sigcore run worlds/cleanup.xml
Then:                   python examples/ros2/find_red_can.py [--timeout 60]
It prints one line for people and, last, one JSON line: {"found": ..., "x": ..., "y": ..., "z": ..., ...}.
"""

import argparse
import json
import time

import numpy as np
import rclpy
from _ready import wait_ready
from geometry_msgs.msg import Twist
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo, Image

CAMERA = "/robot_000/head_rgbd"
CENTRED = 3.0
"""How close [px] the can's centre column must be to the principal point before the robot stops."""


def red_pixels(msg: Image) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the biggest red thing in an rgb8 image: red pixels are grouped into runs of columns (a gap of
    more than 2 columns starts a new one) and the run with the most pixels wins (the red apple further away is
    red too, and smaller)."""
    rgb = np.frombuffer(bytes(msg.data), dtype=np.uint8).reshape(msg.height, msg.width, 3).astype(int)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    rows, cols = np.nonzero((r > 100) & (r > 2 * g) & (r > 2 * b))
    if len(cols) == 0:
        return rows, cols
    columns = np.unique(cols)
    runs = np.split(columns, np.flatnonzero(np.diff(columns) > 3) + 1)
    best = max(runs, key=lambda run: int(np.isin(cols, run).sum()))
    keep = np.isin(cols, best)
    return rows[keep], cols[keep]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--timeout", type=float, default=60.0, help="give up after this many wall seconds")
    args = ap.parse_args()
    rclpy.init()
    node = rclpy.create_node("find_red_can")
    wait_ready(node)
    images: dict[str, object] = {}
    depths: dict[int, Image] = {}  # stamp [ns] -> depth image, to pair it with the colour image of the same step

    def keep_depth(m: Image) -> None:
        depths[m.header.stamp.sec * 10**9 + m.header.stamp.nanosec] = m
        for old in sorted(depths)[:-10]:
            del depths[old]

    node.create_subscription(Image, f"{CAMERA}/image_raw", lambda m: images.update(rgb=m), qos_profile_sensor_data)
    node.create_subscription(Image, f"{CAMERA}/depth/image_raw", keep_depth, qos_profile_sensor_data)
    node.create_subscription(CameraInfo, f"{CAMERA}/camera_info", lambda m: images.update(info=m),
                             qos_profile_sensor_data)
    cmd = node.create_publisher(Twist, "/robot_000/cmd_vel", 10)
    end = time.monotonic() + args.timeout
    result = {"found": False}
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
        rgb, info = images.get("rgb"), images.get("info")
        if rgb is None or info is None:
            continue
        f, cx, cy = info.k[0], info.k[2], info.k[5]
        rows, cols = red_pixels(rgb)
        turn = Twist()
        if len(cols) == 0:
            turn.angular.z = 0.4  # nothing red in view: look further left
        elif abs(cols.mean() - cx) > CENTRED:
            turn.angular.z = float(np.clip(-0.8 * (cols.mean() - cx) / f, -0.3, 0.3))
        else:
            stamp = rgb.header.stamp.sec * 10**9 + rgb.header.stamp.nanosec
            depth_msg = depths.get(stamp)
            if depth_msg is None:
                continue  # the depth image of this step is still on its way
            cmd.publish(Twist())  # stop
            depth = np.frombuffer(bytes(depth_msg.data), dtype=np.float32).reshape(depth_msg.height, depth_msg.width)
            z = float(np.median(depth[rows, cols]))
            u, v = float(cols.mean()), float(rows.mean())
            result = {"found": True, "x": (u - cx) / f * z, "y": (v - cy) / info.k[4] * z, "z": z,
                      "distance": float(np.sqrt(((u - cx) / f * z) ** 2 + ((v - cy) / info.k[4] * z) ** 2 + z * z)),
                      "pixels": int(len(cols)), "u": u, "v": v, "stamp": stamp * 1e-9,
                      "frame": rgb.header.frame_id}
            break
        cmd.publish(turn)
        images.pop("rgb", None)  # act on the next image only
    cmd.publish(Twist())
    if result["found"]:
        print(f"red can at x={result['x']:+.3f} y={result['y']:+.3f} z={result['z']:.3f} m in {result['frame']} "
              f"({result['distance']:.2f} m away, {result['pixels']} pixels, t={result['stamp']:.2f} s)")
    else:
        print(f"no red can found within {args.timeout:g} s")
    print(json.dumps(result), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
