"""Scene shared by the rostest publisher and checkers (metres, radians).

A stereo endoscope 25 cm above the table looking down at the surgical site, the two SARAS tool
tips and PSM1's tip 15 cm below it, each tool's shaft going up towards its trocar (RCM).
Poses are published in the contract's frames (mesa_<side>/sbs_world, PSM1) and the static TF
below links everything to the endoscope's optical frames.
"""
import math

import numpy as np

WIDTH, HEIGHT = 640, 360
K = [500.0, 0.0, 322.5, 0.0, 498.0, 178.2, 0.0, 0.0, 1.0]
D = [-0.2, 0.05, 0.001, -0.0005, 0.0]   # plumb_bob

# Static frames: name -> (parent, xyz, rpy); rotations as in world_frames.yaml (fixed-axis rpy).
FRAMES = {
    'endoscope/left_optical_frame': ('world', (0.05, 0.0025, 0.25), (math.pi, 0.0, 0.0)),
    'endoscope/right_optical_frame': ('world', (0.05, -0.0025, 0.25), (math.pi, 0.0, 0.0)),
    'mesa_left/sbs_world': ('world', (0.0, 0.45, 0.0), (0.0, 0.0, -math.pi / 2)),
    'mesa_right/sbs_world': ('world', (0.0, -0.45, 0.0), (0.0, 0.0, math.pi / 2)),
    'mesa_left/rcm': ('world', (0.02, 0.13, 0.20), (0.0, 0.0, 0.0)),
    'mesa_right/rcm': ('world', (0.02, -0.13, 0.20), (0.0, 0.0, 0.0)),
    'PSM1': ('world', (0.10, -0.08, 0.22), (0.0, 0.0, 0.0)),
    'bones_marker_frame': ('world', (0.0, 0.0, 0.10), (0.0, 0.0, 0.0)),  # for endoscope_sim's bones
}

# Tools: name -> (pose topic, pose frame, tip in world, distance [m] published for it, index)
TOOLS = {
    'mesa_left': ('/mesa_left/ee_pose', 'mesa_left/sbs_world', (0.040, 0.020, 0.10), 0.003, 0),   # red
    'mesa_right': ('/mesa_right/ee_pose', 'mesa_right/sbs_world', (0.062, -0.022, 0.10), 0.012, 1),  # yellow
    'PSM1': ('/dvrk/PSM1/position_cartesian_current', 'PSM1', (0.028, -0.012, 0.11), 0.05, 2),  # green
}
DISTANCES = [0.003, 0.012, 0.05, float('nan')]
EXPECTED_RGB = {'mesa_left': (255, 0, 0), 'mesa_right': (255, 255, 0), 'PSM1': (0, 255, 0)}


def rpy_matrix(r, p, y):
    """Rotation matrix of fixed-axis roll, pitch, yaw: Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def world_from(frame):
    """4x4 transform world <- frame."""
    parent, xyz, rpy = FRAMES[frame]
    assert parent == 'world'
    t = np.eye(4)
    t[:3, :3] = rpy_matrix(*rpy)
    t[:3, 3] = xyz
    return t


def to_frame(frame, p_world):
    """Point given in world, expressed in frame."""
    t = np.linalg.inv(world_from(frame))
    return (t @ np.append(np.asarray(p_world, float), 1.0))[:3]


def quaternion(r, p, y):
    """(x, y, z, w) of fixed-axis rpy."""
    cr, sr = math.cos(r / 2), math.sin(r / 2)
    cp, sp = math.cos(p / 2), math.sin(p / 2)
    cy, sy = math.cos(y / 2), math.sin(y / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


def eye_messages(eye, stamp, data):
    """(CameraInfo, Image) of one eye ('left'/'right') of the test camera: K, plumb_bob D, bgr8 ``data``."""
    from sensor_msgs.msg import CameraInfo, Image  # pylint: disable=import-outside-toplevel
    info = CameraInfo()
    info.header.stamp = stamp
    info.header.frame_id = 'endoscope/%s_optical_frame' % eye
    info.width, info.height = WIDTH, HEIGHT
    info.distortion_model = 'plumb_bob'
    info.D = D
    info.K = K
    info.R = [1, 0, 0, 0, 1, 0, 0, 0, 1]
    # stereo pair with a 5 mm baseline (right P: Tx = -fx * B), as the simulated endoscope's
    info.P = [K[0], 0, K[2], -K[0] * 0.005 if eye == 'right' else 0.0, 0, K[4], K[5], 0, 0, 0, 1, 0]
    img = Image()
    img.header = info.header
    img.width, img.height = WIDTH, HEIGHT
    img.encoding = 'bgr8'
    img.step = 3 * WIDTH
    img.data = data
    return info, img
