"""rovermap.Sequence(path) and rovermap.Mapper(path) take a ROS 2 bag as they take the sequence
directory it was written from. The bag is a rosbag2 directory holding one SQLite file, written
here with Python's sqlite3 and CDR serialised by hand (little-endian, XCDR1)."""
import re
import sqlite3
import struct

import numpy as np

import rovermap
from conftest import run_command


class Cdr:
    """One message: the encapsulation header, then fields aligned to their size."""

    def __init__(self):
        self.out = bytearray(b"\x00\x01\x00\x00")

    def put(self, fmt, *values):
        size = struct.calcsize("<" + fmt.lstrip("0123456789")[0])  # the first field's size
        while (len(self.out) - 4) % size:
            self.out.append(0)
        self.out += struct.pack("<" + fmt, *values)
        return self

    def string(self, text):
        self.put("I", len(text) + 1)
        self.out += text.encode() + b"\0"
        return self

    def sequence(self, data):
        self.put("I", len(data))
        self.out += data
        return self

    def header(self, t, frame_id):
        sec = int(t)
        return self.put("i", sec).put("I", round((t - sec) * 1e9)).string(frame_id)


def tum_lines(path):
    """(t, [tx, ty, tz], [qx, qy, qz, qw]) per line, the numbers as the file has them."""
    rows = []
    for line in path.read_text().splitlines():
        if line and not line.startswith("#"):
            v = [float(x) for x in line.split()]
            rows.append((v[0], v[1:4], v[4:8]))
    return rows


def write_bag(sequence_dir, bag_dir):
    seq = rovermap.Sequence(sequence_dir)
    cam = seq.camera
    yaml = (sequence_dir / "sequence.yaml").read_text()
    translation = [float(x) for x in re.search(r"translation: \[(.*)\]", yaml).group(1).split(",")]
    quaternion = [float(x) for x in re.search(r"quaternion: \[(.*)\]", yaml).group(1).split(",")]
    messages = []  # (topic, type, t, bytes)

    def info(tx):
        m = Cdr().header(0.0, "stereo").put("II", cam.height, cam.width).string("plumb_bob")
        m.put("I", 0).put("9d", *[0.0] * 9).put("9d", *[0.0] * 9)
        m.put("12d", cam.fx, 0, cam.cx, tx, 0, cam.fy, cam.cy, 0, 0, 0, 1, 0)
        return bytes(m.put("6I", *[0] * 6).put("B", 0).out)

    messages.append(("/stereo/left/camera_info", "sensor_msgs/msg/CameraInfo", 0.0, info(0.0)))
    messages.append(("/stereo/right/camera_info", "sensor_msgs/msg/CameraInfo", 0.0,
                     info(-cam.fx * cam.baseline)))
    tf = Cdr().put("I", 1).header(0.0, "base_link").string("stereo_left")
    tf.put("3d", *translation).put("4d", *quaternion)
    messages.append(("/tf_static", "tf2_msgs/msg/TFMessage", 0.0, bytes(tf.out)))
    fix = Cdr().header(0.0, "gps").put("b", 0).put("H", 1)
    fix.put("3d", *[float(re.search(key + r": (\S+)", yaml).group(1))
                    for key in ("latitude", "longitude", "altitude")])
    messages.append(("/fix", "sensor_msgs/msg/NavSatFix", 0.0,
                     bytes(fix.put("9d", *[0.0] * 9).put("B", 0).out)))
    for (t, p, q), frame in zip(tum_lines(sequence_dir / "odometry.tum"), seq):
        odom = Cdr().header(t, "odom").string("base_link").put("3d", *p).put("4d", *q)
        odom.put("78d", *[0.0] * 78)
        messages.append(("/odom", "nav_msgs/msg/Odometry", t, bytes(odom.out)))
        for side, image, stamp in (("left", frame.left, t), ("right", frame.right, t + 0.001)):
            m = Cdr().header(stamp, "stereo").put("II", image.shape[0], image.shape[1])
            m.string("mono8").put("B", 0).put("I", image.shape[1]).sequence(image.tobytes())
            messages.append((f"/stereo/{side}/image_rect", "sensor_msgs/msg/Image", stamp,
                             bytes(m.out)))
    bag_dir.mkdir()
    db = sqlite3.connect(bag_dir / "bag_0.db3")
    db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT "
               "NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)")
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
               "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    topics = {}
    for topic, kind, t, data in messages:
        if topic not in topics:
            topics[topic] = len(topics) + 1
            db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (topics[topic], topic, kind))
        db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                   (topics[topic], round(t * 1e9), data))
    db.commit()
    db.close()
    (bag_dir / "metadata.yaml").write_text(
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
        "  relative_file_paths:\n    - bag_0.db3\n")
    return seq


def test_a_ros2_bag_is_a_sequence_and_a_mappers_recording(datasets, rovermap_exe, tmp_path):
    sequence_dir = datasets / "sim_tiny_stereo"
    directory = write_bag(sequence_dir, tmp_path / "bag")
    keys = {"bag": {"T_body_sensor_source": "tf_static"}}

    bag = rovermap.Sequence(tmp_path / "bag", config=keys)
    assert len(bag) == len(directory) == 3
    np.testing.assert_array_equal(bag.timestamps, directory.timestamps)
    np.testing.assert_array_equal(bag.odometry, directory.odometry)
    np.testing.assert_array_equal(bag.T_body_sensor, directory.T_body_sensor)
    assert bag.camera.fx == directory.camera.fx
    for got, want in zip(bag, directory):
        np.testing.assert_array_equal(got.left, want.left)
        np.testing.assert_array_equal(got.right, want.right)

    # Mapper(path) opens the bag for its description; fed the bag's frames it writes what
    # `rovermap replay` writes from the directory.
    status, _, stderr = run_command(rovermap_exe, "replay", sequence_dir, "--out", tmp_path / "dir")
    assert status == 0, stderr
    mapper = rovermap.Mapper(tmp_path / "bag", config=keys)
    results = [mapper.process_frame(frame) for frame in bag]
    assert results[0].status == "first"
    mapper.write_outputs(tmp_path / "python")
    assert ((tmp_path / "python" / "trajectory.tum").read_bytes()
            == (tmp_path / "dir" / "trajectory.tum").read_bytes())
