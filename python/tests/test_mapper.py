"""rovermap.Mapper fed frame by frame from Python gives what `rovermap replay` gives."""
import numpy as np
import pytest

import rovermap
from conftest import run_command


def replay(exe, sequence, out):
    status, summary, stderr = run_command(exe, "replay", sequence, "--out", out)
    assert status == 0, stderr
    return summary


@pytest.mark.parametrize("name", ["sim_tiny_cloud", "sim_tiny_stereo"])
def test_frame_by_frame_gives_the_replay_outputs(datasets, rovermap_exe, tmp_path, name):
    sequence_dir = datasets / name
    expected = replay(rovermap_exe, sequence_dir, tmp_path / "replay")
    sequence = rovermap.Sequence(sequence_dir)
    mapper = rovermap.Mapper(sequence)
    results = [mapper.process_frame(frame) for frame in sequence]
    assert [r.index for r in results] == list(range(len(sequence)))
    assert results[0].status == "first"
    assert all(r.status in ("registered", "partial") for r in results[1:])
    summary = mapper.write_outputs(tmp_path / "python")
    for key in ("frames", "registered", "partial", "fallbacks", "bad_frames", "distance_m"):
        assert summary[key] == expected[key], key
    assert summary["metrics"]["registered"]["ate_rmse_m"] == pytest.approx(
        expected["metrics"]["registered"]["ate_rmse_m"], rel=1e-12)
    # The same trajectory, to the last digit the files hold.
    for file in ("trajectory.tum", "odometry.tum"):
        assert (tmp_path / "python" / file).read_bytes() == (tmp_path / "replay" / file).read_bytes()
    # ... and the same DEM.
    ours = rovermap.eval.read_dem(tmp_path / "python" / "dem.tif")
    theirs = rovermap.eval.read_dem(tmp_path / "replay" / "dem.tif")
    np.testing.assert_array_equal(ours["elevation"], theirs["elevation"])
    assert ours["geotransform"] == theirs["geotransform"]
    for file in ("map.bt", "drift.csv", "dem.png", "drift.png", "summary.json"):
        assert (tmp_path / "python" / file).stat().st_size > 0
    # The mapper's own view of it.
    np.testing.assert_allclose(mapper.trajectory[-1], results[-1].pose, rtol=0, atol=0)
    assert mapper.trajectory.shape == (len(sequence), 4, 4)
    np.testing.assert_array_equal(mapper.odometry, sequence.odometry)
    np.testing.assert_array_equal(mapper.timestamps, sequence.timestamps)


def test_arrays_and_keywords_instead_of_a_sequence(datasets):
    """Points from numpy with the sensor set up by keywords: the same poses as from the files."""
    sequence = rovermap.Sequence(datasets / "sim_tiny_cloud")
    assert sequence.sensor == "cloud"
    reference = rovermap.Mapper(datasets / "sim_tiny_cloud")
    mapper = rovermap.Mapper(sensor="cloud", camera=sequence.camera,
                             T_body_sensor=sequence.T_body_sensor,
                             origin=(sequence.origin["latitude"], sequence.origin["longitude"],
                                     sequence.origin["altitude"]))
    for frame in sequence:
        expected = reference.process_frame(frame)
        # A copy, as a user's own array would be; the PLY's normals in columns 3-5.
        points = np.array(frame.points)
        if frame.normals is not None:
            points = np.hstack([points, frame.normals])
        got = mapper.process_frame(points, frame.odometry_pose, frame.timestamp,
                                   groundtruth_pose=frame.groundtruth_pose)
        assert got.status == expected.status
        np.testing.assert_array_equal(got.pose, expected.pose)
        np.testing.assert_array_equal(got.correction, expected.correction)
        assert got.correction.shape == (6,) and got.cumulative_correction.shape == (6,)
        assert got.covariance.shape == (6, 6)
        assert got.times["total_ms"] > 0


def test_stereo_images_from_numpy(datasets):
    sequence = rovermap.Sequence(datasets / "sim_tiny_stereo")
    assert sequence.sensor == "stereo"
    by_frame = rovermap.Mapper(sequence)
    by_images = rovermap.Mapper(sequence)
    for frame in list(sequence)[:3]:
        left, right = frame.left, frame.right
        assert left.dtype == np.uint8 and left.shape == (sequence.camera.height,
                                                          sequence.camera.width)
        assert not left.flags.writeable  # a view of the frame's image, not a copy
        a = by_frame.process_frame(frame)
        b = by_images.process_frame((np.array(left), np.array(right)), frame.odometry_pose,
                                    frame.timestamp)
        np.testing.assert_array_equal(a.pose, b.pose)
        assert a.points == b.points > 0


def test_bad_frames_and_skipped_frames_are_results_not_errors(datasets):
    sequence = rovermap.Sequence(datasets / "sim_tiny_cloud")
    mapper = rovermap.Mapper(sequence)
    mapper.process_frame(sequence[0])
    # Two points cannot be registered: dead reckoning carries the pose, nothing is fused.
    frame = sequence[1]
    bad = mapper.process_frame(np.zeros((2, 3)), frame.odometry_pose, frame.timestamp)
    assert bad.status == "bad_frame"
    assert bad.fallback
    assert "points" in bad.detail
    skipped = mapper.skip_frame(sequence[2].odometry_pose, sequence[2].timestamp, "lost in transit")
    assert skipped.status == "bad_frame" and skipped.detail == "lost in transit"
    # The next good frame registers onto the last good one (frame 0).
    good = mapper.process_frame(sequence[3])
    assert good.index == 3
    assert good.status in ("registered", "partial")
    assert len(mapper) == 4


def test_the_mappers_elevation_map_is_a_read_only_view(datasets):
    sequence = rovermap.Sequence(datasets / "sim_tiny_cloud")
    mapper = rovermap.Mapper(sequence)
    for frame in sequence:
        mapper.process_frame(frame)
    dem = mapper.elevation_map
    del mapper  # the view keeps the mapper alive
    assert dem.read_only
    layers = dem.to_numpy()
    assert layers["valid_cells"] == dem.published_cell_count > 100
    assert np.isfinite(layers["elevation"]).sum() == layers["valid_cells"]
    with pytest.raises(ValueError, match="read-only"):
        dem.fuse(np.zeros((3, 3)))
    x0, x1, y0, y1 = layers["extent"]
    rows, cols = layers["elevation"].shape
    assert (x1 - x0) == pytest.approx(cols * dem.cell_size)
    assert (y1 - y0) == pytest.approx(rows * dem.cell_size)


def test_local_map_reference_by_keyword(datasets):
    sequence = rovermap.Sequence(datasets / "sim_tiny_cloud")
    previous = rovermap.Mapper(sequence)
    local = rovermap.Mapper(sequence, reference="local_map")
    same_by_dict = rovermap.Mapper(sequence, config={"mapper": {"reference": "local_map"}})
    for frame in sequence:
        previous.process_frame(frame)
        local.process_frame(frame)
        same_by_dict.process_frame(frame)
    np.testing.assert_array_equal(local.trajectory, same_by_dict.trajectory)
    assert not np.array_equal(local.trajectory, previous.trajectory)
