#!/usr/bin/env python3
"""Build datasets/kitti_stereo51 (a docs/design.md section 4 stereo sequence) from the KITTI
excerpt.

Usage:
    python3 scripts/make_kitti_sequence.py SOURCE_DIR OUT_DIR
    e.g. python3 scripts/make_kitti_sequence.py \
             SOURCE/kitti_odometry_excerpt_stereo51 datasets/kitti_stereo51

SOURCE_DIR holds calib.txt (KITTI P0, P1), poses.txt (51 lines, row-major 3x4 T_cam0_camk),
image_l/NNNNNN.png and image_r/NNNNNN.png (and optionally SHA256SUMS, which is checked).

Writes into OUT_DIR (its README.md is left alone; frames/ is recreated):
    sequence.yaml     stereo camera from calib.txt, T_body_sensor, approximate origin, 10 Hz
    frames/           NNNNNN.left.png / NNNNNN.right.png, byte-identical copies of the source
    groundtruth.tum   T_world_body_k = T_body_cam . T_cam0_camk . T_cam_body (world = body at k=0)
    odometry.tum      dead reckoning from the ground truth with the drift model below
    SHA256SUMS        sha256 of every file except SHA256SUMS and README.md

Python 3 standard library only. Deterministic: the same input gives byte-identical output.
"""

import hashlib
import math
import os
import shutil
import struct
import sys

# ---- Fixed choices (documented in datasets/kitti_stereo51/README.md) -----------------------

FRAME_RATE_HZ = 10.0
WIDTH, HEIGHT = 1226, 370
# Body frame: x forward, y left, z up, origin on the road below the left camera.
BODY_T_CAMERA_TRANSLATION = (0.0, 0.0, 1.65)  # [m] KITTI rig camera height ~1.65 m
BODY_T_CAMERA_RPY_DEG = (-91.2, 0.0, -90.0)  # forward-looking OpenCV camera, 1.2° down (see README)
# Approximate geodetic origin (Karlsruhe, KITTI's region); the excerpt carries no GPS.
ORIGIN = (49.0114, 8.4165, 115.0)  # latitude [deg], longitude [deg], altitude [m]

# Dead-reckoning drift model (the excerpt has no wheel odometry).
SEED = 20120616
ODOM_SCALE_ERROR = 0.03  # translation of each true increment x (1 + 0.03) ...
ODOM_SLIP_SIGMA = 0.01  # ... x (1 + slip), slip ~ N(0, 0.01^2) per step
HEADING_BIAS_DEG_S = 0.2  # yaw error grows by 0.2 deg/s ...
HEADING_RANDOM_WALK_DEG_RT_S = 0.1  # ... plus a random walk of 0.1 deg/sqrt(s)
PITCH_BIAS_DEG_S = 0.05  # pitch error grows by 0.05 deg/s (roll stays true)

TUM_HEADER = "# timestamp tx ty tz qx qy qz qw\n"


# ---- Small deterministic PRNG: splitmix64 + Box-Muller --------------------------------------

class SplitMix64:
    MASK = (1 << 64) - 1

    def __init__(self, seed):
        self.state = seed & self.MASK

    def next_u64(self):
        self.state = (self.state + 0x9E3779B97F4A7C15) & self.MASK
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & self.MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & self.MASK
        return z ^ (z >> 31)

    def uniform(self):
        """Uniform in (0, 1): 53 random bits, never 0."""
        return ((self.next_u64() >> 11) + 0.5) / float(1 << 53)

    def normal(self):
        """Standard normal (Box-Muller, one value per two uniforms; no caching)."""
        u1, u2 = self.uniform(), self.uniform()
        return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


# ---- 3x3 matrices (lists of rows), 3-vectors, rigid transforms (R, t) -----------------------

def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mat_vec(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def vec_add(a, b):
    return [a[i] + b[i] for i in range(3)]


def vec_scale(s, v):
    return [s * x for x in v]


def inverse3(a):
    c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1]
    c01 = a[1][2] * a[2][0] - a[1][0] * a[2][2]
    c02 = a[1][0] * a[2][1] - a[1][1] * a[2][0]
    det = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02
    if abs(det) < 1e-12:
        raise ValueError("singular rotation matrix")
    inv = [[c00, a[0][2] * a[2][1] - a[0][1] * a[2][2], a[0][1] * a[1][2] - a[0][2] * a[1][1]],
           [c01, a[0][0] * a[2][2] - a[0][2] * a[2][0], a[0][2] * a[1][0] - a[0][0] * a[1][2]],
           [c02, a[0][1] * a[2][0] - a[0][0] * a[2][1], a[0][0] * a[1][1] - a[0][1] * a[1][0]]]
    return [[x / det for x in row] for row in inv]


def nearest_rotation(a, iterations=20):
    """Orthonormal polar factor of `a` (Newton iteration R <- (R + R^-T) / 2)."""
    r = [row[:] for row in a]
    for _ in range(iterations):
        r_inv_t = transpose(inverse3(r))
        r = [[0.5 * (r[i][j] + r_inv_t[i][j]) for j in range(3)] for i in range(3)]
    return r


def cos_sin_deg(deg):
    """cos and sin of an angle in degrees; exact for multiples of 90 degrees."""
    if deg == math.floor(deg) and int(deg) % 90 == 0:
        return [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][(int(deg) // 90) % 4]
    rad = math.radians(deg)
    return math.cos(rad), math.sin(rad)


def rot_x(c, s):
    return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]


def rot_y(c, s):
    return [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]


def rot_z(c, s):
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]


def rpy_deg_to_matrix(roll, pitch, yaw):
    """R = Rz(yaw) . Ry(pitch) . Rx(roll) (docs/design.md section 4), angles in degrees."""
    return mat_mul(rot_z(*cos_sin_deg(yaw)), mat_mul(rot_y(*cos_sin_deg(pitch)),
                                                    rot_x(*cos_sin_deg(roll))))


def rpy_rad_to_matrix(roll, pitch, yaw):
    return mat_mul(rot_z(math.cos(yaw), math.sin(yaw)),
                   mat_mul(rot_y(math.cos(pitch), math.sin(pitch)),
                           rot_x(math.cos(roll), math.sin(roll))))


def matrix_to_rpy(r):
    """(roll, pitch, yaw) [rad] with r = Rz(yaw) . Ry(pitch) . Rx(roll)."""
    return (math.atan2(r[2][1], r[2][2]),
            math.asin(-max(-1.0, min(1.0, r[2][0]))),
            math.atan2(r[1][0], r[0][0]))


def matrix_to_quaternion(r):
    """Unit quaternion (x, y, z, w), w >= 0, of a rotation matrix (Shepperd's method)."""
    trace = r[0][0] + r[1][1] + r[2][2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [(r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s, 0.25 * s]
    elif r[0][0] > r[1][1] and r[0][0] > r[2][2]:
        s = 2.0 * math.sqrt(1.0 + r[0][0] - r[1][1] - r[2][2])
        q = [0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s, (r[2][1] - r[1][2]) / s]
    elif r[1][1] > r[2][2]:
        s = 2.0 * math.sqrt(1.0 + r[1][1] - r[0][0] - r[2][2])
        q = [(r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s, (r[0][2] - r[2][0]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + r[2][2] - r[0][0] - r[1][1])
        q = [(r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s, (r[1][0] - r[0][1]) / s]
    norm = math.sqrt(sum(x * x for x in q))
    q = [x / norm for x in q]
    if q[3] < 0.0:
        q = [-x for x in q]
    return q


def compose(a, b):
    """(R_a, t_a) . (R_b, t_b)."""
    return mat_mul(a[0], b[0]), vec_add(mat_vec(a[0], b[1]), a[1])


def invert(a):
    rt = transpose(a[0])
    return rt, vec_scale(-1.0, mat_vec(rt, a[1]))


# ---- Input ----------------------------------------------------------------------------------

def fail(message):
    sys.exit("make_kitti_sequence.py: error: " + message)


def read_numbers(path, count):
    rows = []
    with open(path, "r", encoding="ascii") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            values = [float(x) for x in line.split()]
            if len(values) != count or not all(math.isfinite(v) for v in values):
                fail("%s:%d: expected %d finite numbers" % (path, number, count))
            rows.append(values)
    return rows


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        fail("%s: not a PNG file" % path)
    return struct.unpack(">II", head[16:24])


def sha256_of(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def check_source_checksums(source):
    sums = os.path.join(source, "SHA256SUMS")
    if not os.path.exists(sums):
        return
    with open(sums, "r", encoding="ascii") as f:
        for line in f:
            if not line.strip():
                continue
            digest, name = line.split(None, 1)
            name = name.strip().lstrip("*")
            if sha256_of(os.path.join(source, name)) != digest:
                fail("%s: checksum mismatch for %s" % (sums, name))


# ---- Output formatting ----------------------------------------------------------------------

def fmt(x):
    """Full precision, shortest round-trip decimal; no negative zero."""
    return repr(float(x) + 0.0)


def tum_line(timestamp, pose):
    r, t = pose
    q = matrix_to_quaternion(r)
    return " ".join(["%.9f" % timestamp] + [fmt(v) for v in t] + [fmt(v) for v in q]) + "\n"


def write_text(path, text):
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write(text)


# ---- Main -----------------------------------------------------------------------------------

def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    source, out = argv[1], argv[2]
    check_source_checksums(source)

    # Calibration: P0 (left) and P1 (right) of the rectified pair.
    p0, p1 = read_numbers(os.path.join(source, "calib.txt"), 12)[:2]
    fx, cx, fy, cy = p0[0], p0[2], p0[5], p0[6]
    if (p1[0], p1[2], p1[5], p1[6]) != (fx, cx, fy, cy) or p0[3] != 0.0:
        fail("calib.txt: P0 and P1 do not describe one rectified pair")
    baseline = -p1[3] / fx

    # Poses of the left camera k in left camera 0 (x right, y down, z forward).
    cam_poses = []
    for row in read_numbers(os.path.join(source, "poses.txt"), 12):
        r = nearest_rotation([row[0:3], row[4:7], row[8:11]])  # printed with 7 digits
        cam_poses.append((r, [row[3], row[7], row[11]]))
    n = len(cam_poses)

    image_pairs = []
    for k in range(n):
        left = os.path.join(source, "image_l", "%06d.png" % k)
        right = os.path.join(source, "image_r", "%06d.png" % k)
        for path in (left, right):
            if png_size(path) != (WIDTH, HEIGHT):
                fail("%s: not %dx%d" % (path, WIDTH, HEIGHT))
        image_pairs.append((left, right))
    for side in ("image_l", "image_r"):
        if len(os.listdir(os.path.join(source, side))) != n:
            fail("%s/: expected %d images (one per pose)" % (side, n))

    # Ground truth: T_world_body_k = T_body_cam . T_cam0_camk . T_cam_body.
    body_cam = (rpy_deg_to_matrix(*BODY_T_CAMERA_RPY_DEG), list(BODY_T_CAMERA_TRANSLATION))
    cam_body = invert(body_cam)
    truth = [compose(compose(body_cam, pose), cam_body) for pose in cam_poses]
    stamps = [k / FRAME_RATE_HZ for k in range(n)]

    # Dead reckoning: like sim/Simulator.cpp, each true increment's translation scaled by
    # (1 + scale error)(1 + slip), rotated by the previous estimated attitude; yaw off by
    # bias.dt plus a random walk, pitch off by a bias; roll true; from the true first pose.
    rng = SplitMix64(SEED)
    dt = 1.0 / FRAME_RATE_HZ
    odometry = [truth[0]]
    yaw_error = 0.0
    pitch_error = 0.0
    for k in range(1, n):
        delta = compose(invert(truth[k - 1]), truth[k])
        slip = ODOM_SLIP_SIGMA * rng.normal()
        scale = (1.0 + ODOM_SCALE_ERROR) * (1.0 + slip)
        yaw_error += (math.radians(HEADING_BIAS_DEG_S) * dt +
                      math.radians(HEADING_RANDOM_WALK_DEG_RT_S) * math.sqrt(dt) * rng.normal())
        pitch_error += math.radians(PITCH_BIAS_DEG_S) * dt
        r_prev, t_prev = odometry[-1]
        step = mat_vec(r_prev, vec_scale(scale, delta[1]))
        roll, pitch, yaw = matrix_to_rpy(truth[k][0])
        odometry.append((rpy_rad_to_matrix(roll, pitch + pitch_error, yaw + yaw_error),
                         vec_add(t_prev, step)))

    # Output.
    os.makedirs(out, exist_ok=True)
    frames = os.path.join(out, "frames")
    if os.path.isdir(frames):
        shutil.rmtree(frames)
    os.makedirs(frames)
    for k, (left, right) in enumerate(image_pairs):
        shutil.copyfile(left, os.path.join(frames, "%06d.left.png" % k))
        shutil.copyfile(right, os.path.join(frames, "%06d.right.png" % k))

    qb = matrix_to_quaternion(body_cam[0])
    yaml = (
        "# KITTI odometry excerpt (51 frames), written by scripts/make_kitti_sequence.py:\n"
        "# docs/design.md section 4. Camera from calib.txt; body x forward, y left, z up, "
        "origin on\n"
        "# the road below the left camera; origin approximate (Karlsruhe, no GPS in the excerpt).\n"
        "sensor:\n"
        "  type: stereo\n"
        "  T_body_sensor:\n"
        "    translation: [%s, %s, %s]\n"
        "    rotation_rpy_deg: [%s, %s, %s]  # quaternion [%s, %s, %s, %s]\n"
        "camera:\n"
        "  width: %d\n"
        "  height: %d\n"
        "  fx: %s\n"
        "  fy: %s\n"
        "  cx: %s\n"
        "  cy: %s\n"
        "  baseline: %s  # -P1[0,3] / fx\n"
        "origin:\n"
        "  latitude: %s\n"
        "  longitude: %s\n"
        "  altitude: %s\n"
        "frame_rate: %s\n"
    ) % (tuple(fmt(v) for v in BODY_T_CAMERA_TRANSLATION) +
         tuple(fmt(v) for v in BODY_T_CAMERA_RPY_DEG) + tuple(fmt(v) for v in qb) +
         (WIDTH, HEIGHT, fmt(fx), fmt(fy), fmt(cx), fmt(cy), fmt(baseline)) +
         tuple(fmt(v) for v in ORIGIN) + (fmt(FRAME_RATE_HZ),))
    write_text(os.path.join(out, "sequence.yaml"), yaml)
    write_text(os.path.join(out, "groundtruth.tum"),
               TUM_HEADER + "".join(tum_line(s, p) for s, p in zip(stamps, truth)))
    write_text(os.path.join(out, "odometry.tum"),
               TUM_HEADER + "".join(tum_line(s, p) for s, p in zip(stamps, odometry)))

    names = []
    for directory, subdirs, files in os.walk(out):
        subdirs.sort()
        rel = os.path.relpath(directory, out)
        names += [f if rel == "." else rel.replace(os.sep, "/") + "/" + f for f in files]
    names = sorted(x for x in names if x not in ("SHA256SUMS", "README.md"))
    write_text(os.path.join(out, "SHA256SUMS"),
               "".join("%s  %s\n" % (sha256_of(os.path.join(out, name)), name)
                       for name in names))

    length = sum(math.dist(truth[k - 1][1], truth[k][1]) for k in range(1, n))
    print("%d frames, ground-truth path %.3f m, baseline %.6f m -> %s" % (n, length, baseline, out))


if __name__ == "__main__":
    main(sys.argv)
