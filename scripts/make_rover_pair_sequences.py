#!/usr/bin/env python3
"""Build datasets/rover_erfoud_minnie and datasets/rover_devon_island (docs/design.md section 4
two-frame stereo sequences) from the team's shared copies of two real rover stereo pairs.

Usage:
    python3 scripts/make_rover_pair_sequences.py SHARED_DATASETS_DIR OUT_DATASETS_DIR
    e.g. python3 scripts/make_rover_pair_sequences.py SOURCE datasets

Reads SHARED/rover_erfoud_minnie_pair (deg3_left/, deg3_right/, poses_derived.txt, LICENSE.md)
and SHARED/rover_devon_island_pair (left/, right/, calib/CameraCalibration, LICENSE.md), checks
the files used against their SHA256SUMS, and writes into OUT/rover_erfoud_minnie and
OUT/rover_devon_island (their README.md files are left alone; frames/ is recreated):
    sequence.yaml     stereo camera, T_body_sensor, approximate origin, nominal 1 Hz
    frames/           000000.{left,right}.png, 000001.{left,right}.png
    odometry.tum      two body poses
    LICENSE.md        copied byte for byte
    SHA256SUMS        sha256 of every file except SHA256SUMS and README.md

Erfoud (Minnie): the 640x400 rectified PNGs are copied byte for byte; camera and poses from
poses_derived.txt (the rover's own poses, re-centred on frame 0's position).
Devon Island: the 1280x960 rectified PPMs are converted to 8-bit grey (ITU-R BT.601 luma, as
OpenCV's COLOR_RGB2GRAY) and halved to 640x480 by averaging 2x2 blocks (rounded to nearest);
the calibration is scaled accordingly (f/2, centre (c + 0.5)/2 - 0.5). The pair has no poses:
T_body_sensor comes from a ground-plane fit and frame 1's odometry from the image motion (the
constants below; how they were found is in the folder's README).

Python 3 standard library only. Deterministic: the same input gives byte-identical output.
"""

import hashlib
import os
import shutil
import struct
import sys
import zlib

TUM_HEADER = "# timestamp tx ty tz qx qy qz qw\n"

# ---- Erfoud (Minnie), InFuse field trials, Morocco ------------------------------------------
ERFOUD_SOURCE = "rover_erfoud_minnie_pair"
ERFOUD_FRAMES = [  # (left, right) of frame 0 ("A") and frame 1 ("B", "Next")
    ("deg3_left/MinnieRectDeg3Left.png", "deg3_right/MinnieRectDeg3Right.png"),
    ("deg3_left/MinnieRectDeg3LeftNext.png", "deg3_right/MinnieRectDeg3RightNext.png"),
]
ERFOUD_CAMERA = dict(width=640, height=400, fx=339.532, fy=339.532, cx=318.834, cy=205.771,
                     baseline=0.270282)
# Approximate: the source names no site; Erfoud, Morocco (the InFuse trials' area).
ERFOUD_ORIGIN = (31.43, -4.23, 800.0)

# ---- Devon Island (UTIAS/ASRL), Haughton crater, Canada --------------------------------------
DEVON_SOURCE = "rover_devon_island_pair"
DEVON_FRAMES = [
    ("left/DevonIslandLeft.ppm", "right/DevonIslandRight.ppm"),
    ("left/DevonIslandLeft2.ppm", "right/DevonIslandRight2.ppm"),
]
# Rectified 1280x960 (calib/CameraCalibration), halved.
DEVON_FULL = dict(focal=968.999694824, row=463.537109375, col=635.139038086, baseline=0.239977002)
DEVON_CAMERA = dict(width=640, height=480, fx=DEVON_FULL["focal"] / 2, fy=DEVON_FULL["focal"] / 2,
                    cx=(DEVON_FULL["col"] + 0.5) / 2 - 0.5, cy=(DEVON_FULL["row"] + 0.5) / 2 - 0.5,
                    baseline=DEVON_FULL["baseline"])
# A plane fitted to frame 0's stereo points nearer than 6 m (README): its upward unit normal in
# the camera frame (OpenCV axes) and the camera's height above it [m]. The body frame: z along
# the normal, x the optical axis projected onto the plane, origin on the plane below the camera.
DEVON_GROUND_NORMAL_CAMERA = (-0.0250, -0.9576, -0.2871)
DEVON_CAMERA_HEIGHT_M = 0.915
# Frame 1's dead reckoning: a straight step forward along body x [m] (README: not measured).
DEVON_STEP_M = 0.2
# Haughton crater, Devon Island, Nunavut (approximate; the pair's GPS fix is not recorded).
DEVON_ORIGIN = (75.37, -89.68, 20.0)


def Sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def CheckSums(source_dir, relative_paths):
    sums = {}
    with open(os.path.join(source_dir, "SHA256SUMS")) as f:
        for line in f:
            digest, name = line.split()
            sums[os.path.normpath(name)] = digest
    for rel in relative_paths:
        if sums.get(os.path.normpath(rel)) != Sha256(os.path.join(source_dir, rel)):
            sys.exit(f"{source_dir}/{rel}: checksum differs from SHA256SUMS")


def QuaternionFromMatrix(m):
    """Unit quaternion (x, y, z, w), w >= 0, of a rotation matrix (rows)."""
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        s = 2.0 * (trace + 1.0) ** 0.5
        q = ((m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4)
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]) ** 0.5
        q = (s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s)
    elif m[1][1] > m[2][2]:
        s = 2.0 * (1.0 + m[1][1] - m[0][0] - m[2][2]) ** 0.5
        q = ((m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s)
    else:
        s = 2.0 * (1.0 + m[2][2] - m[0][0] - m[1][1]) ** 0.5
        q = ((m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4, (m[1][0] - m[0][1]) / s)
    n = sum(v * v for v in q) ** 0.5
    q = tuple(v / n for v in q)
    return q if q[3] >= 0 else tuple(-v for v in q)


def TumLine(timestamp, t, q):
    return "%.9f %s\n" % (timestamp, " ".join(repr(float(v)) for v in (*t, *q)))


def CameraYaml(c):
    return ("camera:\n  width: %d\n  height: %d\n  fx: %r\n  fy: %r\n  cx: %r\n  cy: %r\n"
            "  baseline: %r\n" % (c["width"], c["height"], c["fx"], c["fy"], c["cx"], c["cy"],
                                 c["baseline"]))


def OriginYaml(origin):
    return "origin:\n  latitude: %r\n  longitude: %r\n  altitude: %r\nframe_rate: 1.0\n" % origin


def WriteText(path, text):
    with open(path, "w", newline="\n") as f:
        f.write(text)


def WriteSums(out_dir):
    lines = []
    for root, _, files in os.walk(out_dir):
        for name in files:
            rel = os.path.relpath(os.path.join(root, name), out_dir)
            if rel in ("SHA256SUMS", "README.md"):
                continue
            lines.append("%s  %s\n" % (Sha256(os.path.join(out_dir, rel)), rel))
    WriteText(os.path.join(out_dir, "SHA256SUMS"), "".join(sorted(lines, key=lambda s: s[66:])))


def FreshFrames(out_dir):
    frames = os.path.join(out_dir, "frames")
    if os.path.isdir(frames):
        shutil.rmtree(frames)
    os.makedirs(frames)
    return frames


# ---- Minimal PPM reader and grey PNG writer -------------------------------------------------

def ReadPpm(path):
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maxval (whitespace and comments between)
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    if fields[0] != b"P6" or int(fields[3]) != 255:
        sys.exit(f"{path}: not an 8-bit binary PPM (P6)")
    width, height = int(fields[1]), int(fields[2])
    pixels = data[pos + 1:pos + 1 + 3 * width * height]
    return width, height, pixels


def GreyHalved(width, height, rgb):
    """BT.601 luma (OpenCV's fixed-point weights), then the mean of each 2x2 block."""
    grey = bytearray(width * height)
    for i in range(width * height):
        r, g, b = rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]
        grey[i] = (r * 4899 + g * 9617 + b * 1868 + 8192) >> 14
    w2, h2 = width // 2, height // 2
    out = bytearray(w2 * h2)
    for y in range(h2):
        a = 2 * y * width
        b = a + width
        for x in range(w2):
            s = grey[a + 2 * x] + grey[a + 2 * x + 1] + grey[b + 2 * x] + grey[b + 2 * x + 1]
            out[y * w2 + x] = (s + 2) >> 2
    return w2, h2, bytes(out)


def WriteGreyPng(path, width, height, grey):
    def Chunk(kind, payload):
        body = kind + payload
        return struct.pack(">I", len(payload)) + body + struct.pack(">I", zlib.crc32(body))
    raw = b"".join(b"\x00" + grey[y * width:(y + 1) * width] for y in range(height))
    png = (b"\x89PNG\r\n\x1a\n" + Chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
           + Chunk(b"IDAT", zlib.compress(raw, 9)) + Chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(png)


# ---- The two sequences ---------------------------------------------------------------------

def ReadErfoudPoses(path):
    rows = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            parts = line.split()
            rows[parts[0]] = [float(v) for v in parts[-7:]]
    return rows


def Begin(source_dir, out_dir, frame_pairs, other_files):
    """Checks the source files used, copies the license; returns the fresh frames/ folder."""
    CheckSums(source_dir, [p for pair in frame_pairs for p in pair] + other_files + ["LICENSE.md"])
    os.makedirs(out_dir, exist_ok=True)
    shutil.copyfile(os.path.join(source_dir, "LICENSE.md"), os.path.join(out_dir, "LICENSE.md"))
    return FreshFrames(out_dir)


def MakeErfoud(shared, out_root):
    src = os.path.join(shared, ERFOUD_SOURCE)
    out = os.path.join(out_root, "rover_erfoud_minnie")
    frames = Begin(src, out, ERFOUD_FRAMES, ["poses_derived.txt"])
    for k, (left, right) in enumerate(ERFOUD_FRAMES):
        shutil.copyfile(os.path.join(src, left), os.path.join(frames, "%06d.left.png" % k))
        shutil.copyfile(os.path.join(src, right), os.path.join(frames, "%06d.right.png" % k))
    poses = ReadErfoudPoses(os.path.join(src, "poses_derived.txt"))
    cam = poses["L"]  # left camera in the body frame: tx ty tz qx qy qz qw
    norm = sum(v * v for v in cam[3:]) ** 0.5
    q_cam = [v / norm for v in cam[3:]]
    WriteText(os.path.join(out, "sequence.yaml"),
              "# Two real rover stereo frames (InFuse, LAAS-CNRS Minnie), written by\n"
              "# scripts/make_rover_pair_sequences.py: docs/design.md section 4. "
              "Camera: the rectified\n"
              "# 640x400 pair; T_body_sensor: NavCamL in RoverBodyFrame (poses_derived.txt).\n"
              "# Origin approximate (the source names no site); frame rate nominal.\n"
              "sensor:\n  type: stereo\n  T_body_sensor:\n"
              "    translation: [%r, %r, %r]\n" % tuple(cam[:3]) +
              "    quaternion: [%r, %r, %r, %r]\n" % tuple(q_cam) +
              CameraYaml(ERFOUD_CAMERA) + OriginYaml(ERFOUD_ORIGIN))
    # World: LocalTerrainFrame's axes, origin moved to frame A's body position.
    a = poses["A"]
    lines = [TUM_HEADER]
    for k, name in enumerate(("A", "B")):
        p = poses[name]
        t = [p[i] - a[i] for i in range(3)]
        qn = sum(v * v for v in p[3:]) ** 0.5
        q = [v / qn for v in p[3:]]
        if q[3] < 0:
            q = [-v for v in q]
        lines.append(TumLine(float(k), t, q))
    WriteText(os.path.join(out, "odometry.tum"), "".join(lines))
    WriteSums(out)


def Normalised(v):
    n = sum(x * x for x in v) ** 0.5
    return tuple(x / n for x in v)


def Cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def BodyFromGroundNormal(normal_camera):
    """R_body_camera (rows: the body axes in camera coordinates) for a ground normal."""
    z = Normalised(normal_camera)
    along = sum(a * b for a, b in zip(z, (0.0, 0.0, 1.0)))
    x = Normalised(tuple(o - along * n for o, n in zip((0.0, 0.0, 1.0), z)))
    y = Cross(z, x)
    return [list(x), list(y), list(z)]


def MakeDevon(shared, out_root):
    src = os.path.join(shared, DEVON_SOURCE)
    out = os.path.join(out_root, "rover_devon_island")
    frames = Begin(src, out, DEVON_FRAMES, ["calib/CameraCalibration"])
    for k, pair in enumerate(DEVON_FRAMES):
        for side, rel in zip(("left", "right"), pair):
            w, h, rgb = ReadPpm(os.path.join(src, rel))
            w2, h2, grey = GreyHalved(w, h, rgb)
            if (w2, h2) != (DEVON_CAMERA["width"], DEVON_CAMERA["height"]):
                sys.exit(f"{rel}: unexpected size {w}x{h}")
            WriteGreyPng(os.path.join(frames, "%06d.%s.png" % (k, side)), w2, h2, grey)
    WriteText(os.path.join(out, "sequence.yaml"),
              "# Two real rover stereo frames (UTIAS/ASRL Devon Island dataset via InFuse), written\n"
              "# by scripts/make_rover_pair_sequences.py: docs/design.md section 4. "
              "Camera: the rectified\n"
              "# 1280x960 pair halved to 640x480. T_body_sensor from a ground-plane fit (README);\n"
              "# origin approximate (no GPS fix for this pair); frame rate nominal.\n"
              "sensor:\n  type: stereo\n  T_body_sensor:\n"
              "    translation: [0.0, 0.0, %r]\n" % DEVON_CAMERA_HEIGHT_M +
              "    quaternion: [%r, %r, %r, %r]\n" % QuaternionFromMatrix(
                  BodyFromGroundNormal(DEVON_GROUND_NORMAL_CAMERA)) +
              CameraYaml(DEVON_CAMERA) + OriginYaml(DEVON_ORIGIN))
    WriteText(os.path.join(out, "odometry.tum"),
              TUM_HEADER + TumLine(0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)) +
              TumLine(1.0, (DEVON_STEP_M, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
    WriteSums(out)


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    MakeErfoud(argv[1], argv[2])
    MakeDevon(argv[1], argv[2])


if __name__ == "__main__":
    main(sys.argv)
