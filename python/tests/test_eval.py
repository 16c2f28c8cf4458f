"""rovermap.eval: the metrics of `rovermap eval`, on files and arrays."""
import numpy as np
import pytest

import rovermap
from conftest import run_command


def test_files_match_the_command(datasets, rovermap_exe):
    groundtruth = datasets / "sim_tiny_cloud" / "groundtruth.tum"
    estimate = datasets / "sim_tiny_cloud" / "odometry.tum"
    status, expected, _ = run_command(rovermap_exe, "eval", "--estimate", estimate,
                                      "--groundtruth", groundtruth)
    assert status == 0
    got = rovermap.eval.trajectory_metrics(estimate, groundtruth)
    theirs = expected["estimates"][0]
    for key in ("ate_rmse_m", "ate_rmse_origin_m", "pairs", "length_m"):
        assert got[key] == pytest.approx(theirs[key], rel=1e-12), key


def test_arrays_with_and_without_timestamps(datasets):
    stamps, truth = rovermap.eval.read_trajectory(datasets / "sim_tiny_cloud" / "groundtruth.tum")
    assert truth.shape[1:] == (4, 4) and stamps.shape == (len(truth),)
    # A rigidly moved copy: zero error once aligned, at the first pose or in the best fit.
    moved = truth.copy()
    moved[:, :3, 3] += [1.0, -2.0, 0.5]
    metrics = rovermap.eval.trajectory_metrics(moved, truth)
    assert metrics["ate_rmse_m"] == pytest.approx(0.0, abs=1e-9)
    assert metrics["ate_rmse_origin_m"] == pytest.approx(0.0, abs=1e-9)
    # A 10 cm error on one of the poses, associated by time.
    noisy = truth.copy()
    noisy[2, 0, 3] += 0.1
    by_time = rovermap.eval.trajectory_metrics(noisy, truth, estimate_timestamps=stamps,
                                               groundtruth_timestamps=stamps)
    assert by_time["pairs"] == len(truth)
    assert by_time["ate_origin_max_m"] == pytest.approx(0.1, abs=1e-9)
    assert by_time["ate_rmse_origin_m"] == pytest.approx(0.1 / np.sqrt(len(truth)), abs=1e-9)
    # (N, 3, 4) as KITTI files hold them.
    assert rovermap.eval.trajectory_metrics(moved[:, :3, :], truth)["pairs"] == len(truth)
    # Keys of the eval section as keywords.
    segments = rovermap.eval.trajectory_metrics(moved, truth, segment_lengths_m=[0.5])
    assert [s["length_m"] for s in segments["kitti_segments"]] == [0.5]


def test_compare_dems_on_arrays():
    elevation = np.arange(20 * 30, dtype=np.float32).reshape(20, 30) * 0.01
    reference = {"elevation": elevation, "geotransform": (0.0, 0.1, 0.0, 2.0, 0.0, -0.1)}
    dem = {"elevation": elevation + 0.05, "geotransform": reference["geotransform"],
           "stddev": np.full_like(elevation, 0.03)}
    c = rovermap.eval.compare_dems(dem, reference)
    assert c["cells"] == 600
    assert c["bias_m"] == pytest.approx(0.05, abs=1e-6)
    assert c["rmse_m"] == pytest.approx(0.05, abs=1e-6)
    assert c["within_2sigma"] == 1.0
    assert c["coverage"] == 1.0
