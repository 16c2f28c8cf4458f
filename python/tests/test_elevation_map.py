"""rovermap.ElevationMap: fusion, queries, numpy layers and the GeoTIFF."""
import numpy as np
import pytest

import rovermap


def plane_points(height, frame, n=40, spacing=0.05, seed=0):
    rng = np.random.default_rng(seed + frame)
    xs, ys = np.meshgrid(np.arange(n) * spacing, np.arange(n) * spacing)
    xs = xs.ravel() + rng.uniform(0.005, 0.045, xs.size)
    ys = ys.ravel() + rng.uniform(0.005, 0.045, ys.size)
    return np.column_stack([xs, ys, np.full(xs.size, height)])


def test_a_plane_seen_by_three_frames():
    dem = rovermap.ElevationMap(cell_size_m=0.05)
    for frame in range(3):
        stats = dem.fuse(plane_points(0.5, frame), frame=frame)
        assert stats["points"] == 1600
        assert stats["fused"] + stats["candidate"] + stats["swapped"] == 1600
    assert dem.height_at(1.0, 1.0) == pytest.approx(0.5, abs=1e-6)
    assert np.isnan(dem.height_at(10.0, 10.0))
    # Vectorised: arrays broadcast like numpy's.
    heights = dem.height_at(np.array([[0.5], [1.0]]), np.array([0.5, 1.0, 1.5]))
    assert heights.shape == (2, 3)
    np.testing.assert_allclose(heights, 0.5, atol=1e-6)
    assert (dem.variance_at(np.array([1.0]), np.array([1.0])) > 0).all()
    layers = dem.to_numpy()
    z = layers["elevation"]
    assert z.dtype == np.float32 and z.shape == layers["count"].shape == layers["stddev"].shape
    assert np.nanmax(np.abs(z - 0.5)) < 1e-6
    assert layers["valid_cells"] == np.isfinite(z).sum() == dem.published_cell_count
    # Edge cells lack the neighbours the spike test asks for; the inside is published.
    assert dem.published_cell_count >= 36 * 36


def test_an_outlier_does_not_make_a_spike():
    dem = rovermap.ElevationMap(cell_size_m=0.05)
    for frame in range(4):  # a point a cell a frame: the cell has 3 good points by the end
        points = plane_points(0.0, frame)
        if frame == 1:
            points[500, 2] = 2.0  # one stereo mismatch, 2 m off the ground
        dem.fuse(points, frame=frame)
    x, y = plane_points(0.0, 1)[500, :2]
    assert dem.height_at(x, y) == pytest.approx(0.0, abs=1e-6)


def test_write_geotiff_and_read_it_back(tmp_path):
    dem = rovermap.ElevationMap(origin=(46.5191, 6.5668, 400.0), cell_size_m=0.05)
    assert dem.epsg == 32632  # UTM 32N
    for frame in range(3):
        dem.fuse(plane_points(1.25, frame), frame=frame)
    info = dem.write_geotiff(tmp_path / "dem.tif")
    assert info["valid_cells"] == dem.published_cell_count
    raster = rovermap.eval.read_dem(tmp_path / "dem.tif")
    assert raster["epsg"] == 32632
    assert raster["elevation"].shape == (info["height"], info["width"])
    assert np.nanmax(np.abs(raster["elevation"] - 1.25)) < 1e-6
    assert np.isfinite(raster["elevation"]).sum() == info["valid_cells"]
    # The same DEM against itself: no error, full coverage.
    same = rovermap.eval.compare_dems(tmp_path / "dem.tif", tmp_path / "dem.tif")
    assert same["rmse_m"] == 0.0 and same["coverage"] == 1.0


def test_write_geotiff_needs_an_origin(tmp_path):
    dem = rovermap.ElevationMap()
    with pytest.raises(ValueError, match="origin"):
        dem.write_geotiff(tmp_path / "dem.tif")
    assert not (tmp_path / "dem.tif").exists()


def test_covariances_and_bad_shapes():
    dem = rovermap.ElevationMap(min_support=1, min_frame_span=1, min_agreeing_neighbors=0)
    points = np.array([[0.01, 0.01, 1.0]])
    dem.fuse(points, np.diag([1e-4, 1e-4, 4e-4])[None])
    assert dem.variance_at(0.01, 0.01) == pytest.approx(4e-4, rel=1e-6)
    with pytest.raises(ValueError, match="covariances"):
        dem.fuse(points, np.zeros((2, 3, 3)))
    with pytest.raises(ValueError, match="points"):
        dem.fuse(np.zeros((4, 2)))


def test_terrain_layers_of_a_ramp_with_a_box():
    # A 10° ramp (40 × 40 cells of 5 cm) and a 0.25 m box on it: the box is a hazard, the ramp
    # away from it benign, with the ramp's slope.
    dem = rovermap.ElevationMap(cell_size_m=0.05)
    slope = np.tan(np.radians(10.0))
    for frame in range(3):
        points = plane_points(0.0, frame)
        points[:, 2] = slope * points[:, 0]
        box = (points[:, 0] > 1.4) & (points[:, 0] < 1.7) & (points[:, 1] > 0.8) & (points[:, 1] < 1.1)
        points[box, 2] += 0.25
        dem.fuse(points, frame=frame)
    layers = dem.terrain(footprint_m=0.5)
    z = dem.to_numpy()["elevation"]
    assert layers["footprint_cells"] == (11, 11)
    for name in ("slope_deg", "slope_stddev_deg", "roughness_m", "step_m", "traversability",
                 "uncertain"):
        assert layers[name].dtype == np.float32 and layers[name].shape == z.shape
    trav = layers["traversability"]
    assert layers["hazard_cells"] > 0 and layers["benign_cells"] > 100
    assert (trav == 0).sum() >= layers["hazard_cells"] - layers["uncertain_cells"]
    benign = trav > 0
    np.testing.assert_allclose(layers["slope_deg"][benign], 10.0, atol=0.5)
    assert np.nanmax(layers["step_m"]) > 0.25
    with pytest.raises(ValueError, match="terrain.footprint_m"):
        dem.terrain(footprint_m=0.05)
