"""rovermap.register on arrays matches `rovermap register` on the files, and recovers known
transforms."""
import numpy as np
import pytest

import rovermap
from conftest import run_command


def rotation(axis, angle_rad):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle_rad) * k + (1 - np.cos(angle_rad)) * k @ k


def test_version_is_the_projects(datasets):
    cmake = (datasets.parent / "CMakeLists.txt").read_text()
    assert f"project(rovermap VERSION {rovermap.__version__} " in cmake


def test_bunny_from_arrays_matches_the_command(datasets, rovermap_exe):
    source_file = datasets / "stanford_bunny" / "bun045.ply"
    target_file = datasets / "stanford_bunny" / "bun000.ply"
    status, expected, _ = run_command(rovermap_exe, "register", source_file, target_file)
    assert status == 0
    result = rovermap.register(rovermap.read_points(source_file), rovermap.read_points(target_file))
    assert result.status == expected["status"] == "converged"
    assert result.usable
    assert result.iterations == expected["iterations"]
    assert result.inliers == expected["inliers"]
    assert result.sample_points == expected["sample_points"]
    assert result.source_points == expected["source_points"]
    assert result.target_points == expected["target_points"]
    # The same clouds through the same code: equal to the digits JSON prints.
    np.testing.assert_allclose(result.T, np.array(expected["matrix"]), rtol=0, atol=1e-12)
    assert result.rms == pytest.approx(expected["rms"], rel=1e-12)
    assert result.final_dmax == pytest.approx(expected["final_dmax"], rel=1e-12)
    np.testing.assert_allclose(result.covariance, np.array(expected["covariance"]), rtol=1e-9,
                               atol=0)
    assert len(result.trace) == len(expected["trace"])
    for mine, theirs in zip(result.trace, expected["trace"]):
        for key, value in theirs.items():
            assert mine[key] == pytest.approx(value, rel=1e-12), key


def test_paths_and_arrays_give_the_same_result(datasets):
    source_file = datasets / "stanford_bunny" / "bun045.ply"
    target_file = datasets / "stanford_bunny" / "bun000.ply"
    from_files = rovermap.register(source_file, str(target_file))
    from_arrays = rovermap.register(rovermap.read_points(source_file),
                                    rovermap.read_points(target_file))
    np.testing.assert_array_equal(from_files.T, from_arrays.T)


def test_recovers_a_known_transform(datasets):
    """Property check: the bunny moved by T comes back onto itself with T⁻¹."""
    target = rovermap.read_points(datasets / "stanford_bunny" / "bun000.ply")
    T = np.eye(4)
    T[:3, :3] = rotation([0.3, 1.0, 0.2], np.radians(8.0))
    T[:3, 3] = [0.005, -0.004, 0.003]  # metres: the bunny is 0.15 m across
    source = target @ T[:3, :3].T + T[:3, 3]
    result = rovermap.register(source, target)
    assert result.usable
    expected = np.linalg.inv(T)
    residual = np.linalg.inv(expected) @ result.T
    angle = np.degrees(np.arccos(np.clip((np.trace(residual[:3, :3]) - 1) / 2, -1, 1)))
    assert angle < 0.01
    assert np.linalg.norm(residual[:3, 3]) < 1e-5
    assert result.inlier_ratio > 0.95


def test_init_and_normals_columns(datasets):
    target = rovermap.read_points(datasets / "stanford_bunny" / "bun000.ply")
    T = np.eye(4)
    T[:3, :3] = rotation([0, 0, 1], np.radians(30.0))
    source = target @ T[:3, :3].T
    # 30° about z is beyond the default's reach from the identity only if unseeded; seeded with
    # the truth the matcher stays there.
    seeded = rovermap.register(source, target, init=np.linalg.inv(T))
    assert seeded.usable
    np.testing.assert_allclose(seeded.T, np.linalg.inv(T), atol=1e-6)
    # (N, 6): normals in columns 3-5, as in an .xyz file.
    normals = np.tile([0.0, 0.0, 1.0], (len(target), 1))
    with_normals = rovermap.register(np.hstack([source, normals @ T[:3, :3].T]),
                                     np.hstack([target, normals]), init=np.linalg.inv(T))
    assert with_normals.usable


def test_overrides_config_dict_and_file_agree(datasets, tmp_path):
    source = datasets / "stanford_bunny" / "bun045.ply"
    target = datasets / "stanford_bunny" / "bun000.ply"
    by_keyword = rovermap.register(source, target, max_iterations=3)
    assert by_keyword.iterations == 3
    assert by_keyword.status == "max_iterations"
    by_dict = rovermap.register(source, target, config={"registration.max_iterations": 3})
    nested = rovermap.register(source, target, config={"registration": {"max_iterations": 3}})
    config_file = tmp_path / "c.yaml"
    config_file.write_text("registration:\n  max_iterations: 3\n")
    by_file = rovermap.register(source, target, config=config_file)
    for other in (by_dict, nested, by_file):
        np.testing.assert_array_equal(other.T, by_keyword.T)
    # Keyword arguments come after the file, as --set after --config.
    assert rovermap.register(source, target, config=config_file, max_iterations=5).iterations == 5


def test_curve_geometry_from_the_defaults():
    """geometry="curve" alone works (the residual follows the geometry), as with --set."""
    t = np.linspace(0, 4 * np.pi, 200)
    curve = np.column_stack([np.cos(t), np.sin(t), 0.1 * t])
    T = np.eye(4)
    T[:3, :3] = rotation([1, 0, 0], np.radians(3.0))
    T[:3, 3] = [0.02, 0.0, -0.01]
    result = rovermap.register(curve @ T[:3, :3].T + T[:3, 3], curve, geometry="curve")
    assert result.usable
    np.testing.assert_allclose(result.T @ T, np.eye(4), atol=1e-3)


def test_noise_floor_of_a_plane(tmp_path):
    """A noisy plane without normals: x and y hold about their noise floor, z none of it; a
    bumpy surface holds several times its floor."""
    rng = np.random.default_rng(3)
    g = np.arange(-4.0, 4.0, 0.05)
    x, y = np.meshgrid(g, g)
    def surface(bump):
        z = bump * np.sin(2.0 * x) * np.cos(1.7 * y)
        return np.column_stack([x.ravel(), y.ravel(), (z + rng.normal(0, 0.01, z.shape)).ravel()])
    for bump, low, high in ((0.0, 0.0, 3.0), (0.2, 6.0, np.inf)):
        result = rovermap.register(surface(bump), surface(bump))
        assert result.usable
        for axis in (3, 4):
            ratio = result.information[axis, axis] / result.noise_information[axis, axis]
            assert low < ratio < high, (bump, axis, ratio)
        assert result.noise_information[5, 5] < 1e-3 * result.information[5, 5]
