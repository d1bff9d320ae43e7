"""Step a paused simulation of tests/data/sim/camera.xml by argv[1] steps and collect what its camera publishes:
colour and depth images, both CameraInfos, and the static transforms to the camera's frames."""

import sys

import numpy as np
from common import Client, emit
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CameraInfo, Image
from sigcore_msgs.srv import CaptureView, DistanceSensor
from simulation_interfaces.srv import StepSimulation
from tf2_msgs.msg import TFMessage

c = Client("camera_watch")
c.wait_ready()
deep = QoSProfile(depth=200, reliability=ReliabilityPolicy.RELIABLE)
rgb, depth, info, depth_info = (c.listen(cls, f"/bot/head{topic}", deep) for cls, topic in (
    (Image, "/image_raw"), (Image, "/depth/image_raw"), (CameraInfo, "/camera_info"),
    (CameraInfo, "/depth/camera_info")))
static = c.listen(TFMessage, "/tf_static", QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                                                       durability=DurabilityPolicy.TRANSIENT_LOCAL))
c.wait_for(lambda: c.node.count_publishers("/bot/head/depth/image_raw") > 0 and bool(static), 20.0)
c.spin(0.5)
steps = int(sys.argv[1])
result = c.call(StepSimulation, "/step_simulation", timeout=120.0, steps=steps)
expected = steps // 50
c.wait_for(lambda: min(len(rgb), len(depth), len(info), len(depth_info)) >= expected, 30.0)
c.spin(0.5)


def stamp(m) -> float:
    return m.header.stamp.sec + m.header.stamp.nanosec * 1e-9


last = depth[-1] if depth else None
centre = None
if last is not None:
    d = np.frombuffer(bytes(last.data), dtype=np.float32).reshape(last.height, last.width)
    centre = float(d[last.height // 2, last.width // 2])
red_cols = []
if rgb:
    m = rgb[-1]
    img = np.frombuffer(bytes(m.data), dtype=np.uint8).reshape(m.height, m.width, 3).astype(int)
    red = (img[..., 0] > 90) & (img[..., 1] < 60) & (img[..., 2] < 60)
    red_cols = np.nonzero(red)[1].tolist()
frames = {t.child_frame_id: {"parent": t.header.frame_id,
                             "xyz": [t.transform.translation.x, t.transform.translation.y, t.transform.translation.z],
                             "wxyz": [t.transform.rotation.w, t.transform.rotation.x, t.transform.rotation.y,
                                      t.transform.rotation.z]}
          for msg in static for t in msg.transforms}
view = c.call(CaptureView, "/bot_captureView", timeout=30.0, camera="")
distance = c.call(DistanceSensor, "/bot_distanceSensor", timeout=30.0, camera="head")
wrong = c.call(DistanceSensor, "/bot_distanceSensor", timeout=30.0, camera="eyes")
services = {
    "view": None if view is None else {
        "success": view.success, "message": view.message, "stamp": stamp(view.image),
        "encoding": view.image.encoding, "w": view.image.width, "depth_encoding": view.depth.encoding,
        "frame": view.image.header.frame_id, "k": list(view.camera_info.k), "bytes": len(view.image.data),
        "centre": float(np.frombuffer(bytes(view.depth.data), dtype=np.float32).reshape(
            view.depth.height, view.depth.width)[view.depth.height // 2, view.depth.width // 2])},
    "distance": None if distance is None else {"success": distance.success, "distance": distance.distance},
    "wrong": None if wrong is None else {"success": wrong.success, "message": wrong.message}}
emit({"services": services, "stepped": result is not None and result.result.result == 1,
      "rgb_stamps": [stamp(m) for m in rgb], "depth_stamps": [stamp(m) for m in depth],
      "info_stamps": [stamp(m) for m in info], "depth_info_stamps": [stamp(m) for m in depth_info],
      "rgb": {"encoding": rgb[-1].encoding, "w": rgb[-1].width, "h": rgb[-1].height, "step": rgb[-1].step,
              "frame": rgb[-1].header.frame_id} if rgb else None,
      "depth": {"encoding": last.encoding, "w": last.width, "h": last.height, "step": last.step,
                "frame": last.header.frame_id, "centre": centre} if last is not None else None,
      "k": list(info[-1].k) if info else None, "p": list(info[-1].p) if info else None,
      "depth_k": list(depth_info[-1].k) if depth_info else None, "red_cols": red_cols,
      "frames": {k: v for k, v in frames.items() if k.startswith("head")}})
