"""Errors carry over from the commands: a bad key or value is a ValueError naming the key, a file
that cannot be read or written an OSError naming the file."""
import os

import numpy as np
import pytest

import rovermap

CLOUD = np.random.default_rng(0).uniform(-1, 1, (100, 3))


def test_unknown_key_names_it_and_the_closest_known_key():
    with pytest.raises(ValueError, match=r"registration\.max_iteration\b.*max_iterations"):
        rovermap.register(CLOUD, CLOUD, max_iteration=3)
    with pytest.raises(ValueError, match=r"mapper\.refrence"):
        rovermap.Mapper(sensor="cloud", origin=(46.5, 6.5), refrence="local_map")
    with pytest.raises(ValueError, match=r"registration\.nope"):
        rovermap.register(CLOUD, CLOUD, config={"registration": {"nope": 1}})


def test_bad_values_name_the_key():
    with pytest.raises(ValueError, match=r"registration\.max_iterations: must be > 0"):
        rovermap.register(CLOUD, CLOUD, max_iterations=-3)
    with pytest.raises(ValueError, match=r"registration\.geometry"):
        rovermap.register(CLOUD, CLOUD, geometry="blob")
    with pytest.raises(ValueError, match=r"dem\.cell_size_m"):
        rovermap.ElevationMap(cell_size_m=0.0)
    with pytest.raises(ValueError, match=r"registration\.max_iterations"):
        rovermap.register(CLOUD, CLOUD, max_iterations=1.5)  # not an int
    with pytest.raises(ValueError, match=r"mapper\.local_map_frames"):
        rovermap.Mapper(sensor="cloud", origin=(46.5, 6.5), local_map_frames=0)


def test_a_config_file_with_a_bad_key_names_file_and_line(tmp_path):
    config = tmp_path / "bad.yaml"
    config.write_text("registration:\n  max_iterations: 10\n  bogus: 2\n")
    with pytest.raises(ValueError, match=r"bad\.yaml:3.*registration\.bogus"):
        rovermap.register(CLOUD, CLOUD, config=config)


def test_missing_files_are_os_errors_naming_the_file(tmp_path, datasets):
    missing = tmp_path / "nope.ply"
    with pytest.raises(OSError, match="nope.ply"):
        rovermap.register(missing, CLOUD)
    with pytest.raises(OSError, match="nope.ply"):
        rovermap.read_points(missing)
    with pytest.raises(OSError, match="missing.yaml"):
        rovermap.register(CLOUD, CLOUD, config=tmp_path / "missing.yaml")
    with pytest.raises(OSError, match="no_such_sequence"):
        rovermap.Sequence(tmp_path / "no_such_sequence")
    with pytest.raises(OSError, match="no_such.tum"):
        rovermap.eval.trajectory_metrics(tmp_path / "no_such.tum", tmp_path / "no_such.tum")
    with pytest.raises(OSError, match="no_such.tif"):
        rovermap.eval.read_dem(tmp_path / "no_such.tif")


def test_a_truncated_file_names_file_and_line(tmp_path):
    bad = tmp_path / "bad.xyz"
    bad.write_text("0 0 0\n1 1 1\n2 2 oops\n")
    with pytest.raises(OSError, match=r"bad\.xyz:3"):
        rovermap.read_points(bad)


def test_bad_arrays_name_the_argument():
    with pytest.raises(ValueError, match="source.*shape"):
        rovermap.register(np.zeros((10, 2)), CLOUD)
    with pytest.raises(ValueError, match="target"):
        rovermap.register(CLOUD, object())
    with pytest.raises(ValueError, match="init"):
        rovermap.register(CLOUD, CLOUD, init=np.eye(3))
    skewed = np.eye(4)
    skewed[0, 1] = 0.5
    with pytest.raises(ValueError, match="init.*rigid"):
        rovermap.register(CLOUD, CLOUD, init=skewed)


def test_mapper_input_errors(datasets, tmp_path):
    sequence = rovermap.Sequence(datasets / "sim_tiny_stereo")
    mapper = rovermap.Mapper(sequence)
    frame = sequence[0]
    with pytest.raises(ValueError, match="stereo"):
        mapper.process_frame(np.zeros((100, 3)), frame.odometry_pose, frame.timestamp)
    with pytest.raises(ValueError, match="left"):
        mapper.process_frame((np.zeros((10, 10), np.uint8), frame.right), frame.odometry_pose, 0.0)
    with pytest.raises(ValueError, match="left"):
        mapper.process_frame((np.array(frame.left, np.float32), frame.right),
                             frame.odometry_pose, 0.0)
    with pytest.raises(ValueError, match="odometry_pose"):
        mapper.process_frame((frame.left, frame.right), np.full((4, 4), np.nan), 0.0)
    with pytest.raises(ValueError, match="odometry_pose"):
        mapper.process_frame((frame.left, frame.right))
    assert len(mapper) == 0  # nothing was processed
    with pytest.raises(ValueError, match="origin"):
        rovermap.Mapper(sensor="cloud")
    with pytest.raises(ValueError, match="camera"):
        rovermap.Mapper(sensor="stereo", origin=(46.5, 6.5))
    with pytest.raises(ValueError, match="sensor"):
        rovermap.Mapper(sensor="lidar", origin=(46.5, 6.5))


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere")
def test_unwritable_output_is_an_os_error_naming_the_file(datasets, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    mapper = rovermap.Mapper(datasets / "sim_tiny_cloud")
    mapper.process_frame(rovermap.Sequence(datasets / "sim_tiny_cloud")[0])
    with pytest.raises(OSError, match="locked"):
        mapper.write_outputs(locked)


def test_output_folder_that_is_a_file_is_an_os_error(datasets, tmp_path):
    blocker = tmp_path / "out"
    blocker.write_text("a file where the folder should be")
    mapper = rovermap.Mapper(datasets / "sim_tiny_cloud")
    mapper.process_frame(rovermap.Sequence(datasets / "sim_tiny_cloud")[0])
    with pytest.raises(OSError, match="out"):
        mapper.write_outputs(blocker)
    with pytest.raises(OSError, match="out"):
        mapper.write_outputs(blocker / "sub")
