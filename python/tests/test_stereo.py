"""stereodet.stereo on hand-made pairs: known disparities, formulas checked with numpy, the fused
encoder against the separate functions, and bad images raising ValueError."""

import numpy as np
import pytest

from stereodet import kitti, stereo

CALIB = kitti.Calibration.kitti_like()
SHIFT = 12  # px: the disparity of the synthetic pair


def textured_pair(rows=96, cols=240, shift=SHIFT, seed=1):
    """A random texture and the same texture seen `shift` px further left by the right camera:
    right(u - shift) = left(u), so every matchable pixel has disparity `shift`."""
    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, (rows // 4, cols // 4, 3), dtype=np.uint8)
    left = np.ascontiguousarray(np.kron(small, np.ones((4, 4, 1), dtype=np.uint8)))
    left = left + rng.integers(0, 8, left.shape, dtype=np.uint8)  # fine texture too
    right = np.roll(left, -shift, axis=1)
    return left, right


def test_disparity_of_a_shifted_texture_is_the_shift():
    left, right = textured_pair()
    d = stereo.disparity(left, right, num_disparities=32)
    assert d.dtype == np.float32 and d.shape == left.shape[:2]
    valid = d > 0
    assert valid.mean() > 0.5
    assert np.mean(abs(d[valid] - SHIFT) <= 0.25) > 0.95  # sub-pixel steps of 1/16 px
    assert set(np.unique(d[~valid])) == {-1.0}  # invalid pixels are -1, never 0
    # Grey images give the same; SGBM finds the shift too.
    grey = stereo.disparity(left.mean(axis=2).astype(np.uint8), right.mean(axis=2).astype(np.uint8),
                            num_disparities=32)
    assert np.mean(abs(grey[grey > 0] - SHIFT) <= 0.25) > 0.95
    sgbm = stereo.disparity(left, right, method="sgbm", num_disparities=32, sgbm={"block_size": 5})
    assert np.mean(abs(sgbm[sgbm > 0] - SHIFT) <= 0.25) > 0.95


def test_match_scale_gives_the_full_size_disparity():
    """match_scale=0.5 matches at half the size and returns the full size, in full-size px."""
    left, right = textured_pair()
    disparity = stereo.disparity(left, right, num_disparities=32, match_scale=0.5)
    assert disparity.shape == left.shape[:2]
    valid = disparity[:, 64:] > 0
    assert valid.mean() > 0.5
    assert np.median(disparity[:, 64:][valid]) == pytest.approx(SHIFT, abs=0.5)
    with pytest.raises(ValueError, match="match_scale"):
        stereo.disparity(left, right, match_scale=0.0)


def test_every_opencv_matcher_setting_is_a_keyword():
    left, right = textured_pair()
    o = stereo.DisparityOptions(method="sgbm", num_disparities=32,
                                sgbm={"mode": "sgbm3way", "colour": True, "p1": 100, "p2": 400},
                                wls={"enabled": True, "lambda_": 4000.0})
    assert (o.sgbm.mode, o.sgbm.colour, o.sgbm.p1, o.sgbm.p2) == ("sgbm3way", True, 100, 400)
    assert (o.wls.enabled, o.wls.lambda_, o.wls.sigma_color) == (True, 4000.0, 1.5)
    assert stereo.DisparityOptions().sgbm.p1 is None  # the per-pixel rule by default
    # SGBM on colour finds the shift of the colour pair as grey SGBM does.
    colour = stereo.disparity(left, right, method="sgbm", num_disparities=32,
                              sgbm={"colour": True})
    assert np.mean(abs(colour[colour > 0] - SHIFT) <= 0.25) > 0.95
    # The WLS post-filter fills the holes: denser than BM alone, still the shift where BM matched.
    flat = left.copy()
    flat[30:60, 100:150] = 128  # a textureless patch, where BM finds nothing
    flat_right = np.roll(flat, -SHIFT, axis=1)
    bm = stereo.disparity(flat, flat_right, num_disparities=32)
    wls = stereo.disparity(flat, flat_right, num_disparities=32, wls={"enabled": True})
    inside = (slice(8, -8), slice(48, -8))  # the matcher's margins and search range left out
    assert (wls[inside] > 0).mean() > (bm[inside] > 0).mean()
    assert np.median(abs(wls[(bm > 0) & (wls > 0)] - SHIFT)) <= 0.5
    with pytest.raises(ValueError, match="mode: unknown"):
        stereo.DisparityOptions(sgbm={"mode": "fast"})
    with pytest.raises(ValueError, match="P1 < P2"):
        stereo.disparity(left, right, method="sgbm", num_disparities=32,
                         sgbm={"p1": 500, "p2": 400})
    with pytest.raises(ValueError, match="WLS lambda"):
        stereo.disparity(left, right, num_disparities=32, wls={"enabled": True, "lambda_": -1.0})


def test_ground_tolerance_settings_are_keywords():
    o = stereo.GroundPlaneOptions(warn_tilt_deg=2.5, suspect_uses_prior=True)
    assert (o.warn_tilt_deg, o.warn_camera_height_m, o.suspect_uses_prior) == (2.5, 0.25, True)
    with pytest.raises(ValueError, match="warn_tilt_deg"):
        stereo.GroundPlaneOptions(warn_tilt_deg=-1.0).check()


def synthetic_disparity():
    d = np.full((40, 60), -1.0, dtype=np.float32)
    d[10:, 5:] = np.linspace(4, 60, d[10:, 5:].size, dtype=np.float32).reshape(30, 55)
    return d


def test_depth_is_f_b_over_d():
    d = synthetic_disparity()
    depth = stereo.depth_from_disparity(d, CALIB)
    valid = d > 0
    assert np.all(np.isnan(depth[~valid]))
    expected = CALIB.focal_px * CALIB.baseline_m / d[valid].astype(np.float64)
    assert np.allclose(depth[valid], expected, rtol=1e-6, atol=0)


def test_points_and_heights_follow_the_pinhole_model():
    d = synthetic_disparity()
    points = stereo.points_in_rect(d, CALIB)
    assert points.shape == (40, 60, 3) and points.dtype == np.float32
    v, u = np.nonzero(d > 0)
    z = CALIB.focal_px * CALIB.baseline_m / d[v, u].astype(np.float64)
    k = CALIB.projection[2][:, :3]
    rays = np.linalg.solve(k, np.stack([u, v, np.ones_like(u)]).astype(np.float64))
    expected = CALIB.camera_centre_in_rect(2)[:, None] + z * rays
    assert np.allclose(points[v, u].T, expected, rtol=1e-5, atol=1e-5)
    # Height above the nominal plane (flat road 1.65 m below the rect origin): 1.65 - y.
    height = stereo.height_from_disparity(d, CALIB)
    assert np.allclose(height[v, u], 1.65 - expected[1], rtol=1e-5, atol=1e-5)
    tilted = {"normal_in_rect": np.array([0.0, -1.0, 0.0]), "offset_m": 2.0}
    assert np.allclose(stereo.height_from_disparity(d, CALIB, tilted)[v, u], 2.0 - expected[1],
                       rtol=1e-5, atol=1e-5)


def test_quantization_formulas():
    h = np.array([[np.nan, -5.0, -1.0, 0.0, 1.5, 4.0, 9.0]], dtype=np.float32)
    codes = stereo.quantize_height(h)
    assert codes.dtype == np.uint16
    assert codes.tolist() == [[0, 1, 1, 103, 256, 511, 511]]  # 1 + round((h + 1) / 5 * 510)
    assert stereo.quantize_height(h, min_m=0, max_m=1).tolist()[0][3:5] == [1, 511]
    depth = np.array([[np.nan, 0.0, 40.0, 80.0]], dtype=np.float32)
    assert stereo.quantize_depth(depth, bits=8).tolist() == [[0, 1, 128, 255]]


def test_rgbh_packs_and_unpacks_exactly():
    rng = np.random.default_rng(2)
    bgr = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    codes = rng.integers(0, 512, (20, 30), dtype=np.uint16)
    packed = stereo.pack_rgbh(bgr, codes)
    assert packed.dtype == np.uint8 and packed.shape == (20, 30, 3)
    # stereo/rgbh.h's bit layout: B = b4..b0 h2 h1 h0, G = g.. h5 h4 h3, R = r.. h8 h7 h6.
    assert np.array_equal(packed[..., 0], (bgr[..., 0] >> 3 << 3) | (codes & 7))
    assert np.array_equal(packed[..., 2], (bgr[..., 2] >> 3 << 3) | (codes >> 6))
    bgr5, back = stereo.unpack_rgbh(packed)
    assert np.array_equal(bgr5, bgr >> 3) and np.array_equal(back, codes)
    planar = stereo.rgbh_planar(packed)
    assert planar.shape == (4, 20, 30) and planar.dtype == np.float32
    assert np.allclose(planar[0], (bgr[..., 2] >> 3) / 31) and np.allclose(planar[3], codes / 511)
    assert stereo.rgbh_planar(packed, "rgbh-fixed").shape == (3, 20, 30)
    rgb = stereo.rgb_planar(bgr)
    assert np.allclose(rgb, bgr[..., ::-1].transpose(2, 0, 1) / 255)
    rgbd = stereo.rgbd_planar(bgr, codes, codes, bits=16)
    assert rgbd.shape == (5, 20, 30) and np.allclose(rgbd[3], codes / 65535)
    with pytest.raises(ValueError, match="0..511"):
        stereo.pack_rgbh(bgr, np.full((20, 30), 600, dtype=np.uint16))


def test_point_cloud_is_the_valid_pixels_in_the_velo_frame():
    d = synthetic_disparity()
    left = np.full((40, 60, 3), 51, dtype=np.uint8)
    cloud = stereo.point_cloud(d, left, CALIB, max_depth_m=1e9, min_height_m=-1e9,
                               max_height_m=1e9)
    assert cloud.dtype == np.float32 and cloud.shape == (np.count_nonzero(d > 0), 4)
    assert np.allclose(cloud[:, 3], 51 / 255)
    # Back to rect: the same points as points_in_rect, in row-major pixel order.
    velo = np.c_[cloud[:, :3].astype(np.float64), np.ones(len(cloud))]
    rect = (CALIB.rect_from_velo @ velo.T).T[:, :3]
    assert np.allclose(rect, stereo.points_in_rect(d, CALIB)[d > 0], rtol=1e-4, atol=1e-4)
    # Truncation: nothing beyond 20 m.
    near = stereo.point_cloud(d, left, CALIB, max_depth_m=20.0)
    depth = stereo.depth_from_disparity(d, CALIB)
    assert len(near) <= np.count_nonzero(depth <= 20.0) and len(near) > 0


def test_the_fused_encoder_equals_the_separate_functions():
    left, right = textured_pair(rows=128, cols=320)
    out = stereo.encode(left, right, CALIB, outputs=("rgbh", "depth", "points"),
                        disparity={"num_disparities": 32})
    d = stereo.disparity(left, right, num_disparities=32)
    assert np.array_equal(out["disparity"], d)
    assert np.array_equal(out["network_image"], left)
    ground = out["ground"]
    assert set(ground) >= {"normal_in_rect", "offset_m", "fitted", "reason"}
    height = stereo.height_from_disparity(d, CALIB, ground)
    assert np.array_equal(out["height_code"], stereo.quantize_height(height))
    assert np.array_equal(out["rgbh"], stereo.pack_rgbh(left, out["height_code"]))
    assert np.array_equal(out["depth_code"],
                          stereo.quantize_depth(stereo.depth_from_disparity(d, CALIB)))
    assert np.array_equal(out["points"], stereo.point_cloud(d, left, CALIB, ground))
    # Only what was asked for; blur changes the network image only.
    plain = stereo.encode(left, right, CALIB, blur={"sigma_px": 2.0},
                          disparity={"num_disparities": 32})
    assert "points" not in plain and "depth_code" not in plain
    assert not np.array_equal(plain["network_image"], left)
    assert np.array_equal(plain["disparity"], d)


def test_ground_fit_falls_back_on_too_few_points():
    fit = stereo.fit_ground_plane(synthetic_disparity()[:5], CALIB)
    assert fit["fitted"] is False and "too few stereo points" in fit["reason"]
    assert fit["offset_m"] == 1.65


def test_options_are_keyword_arguments_with_the_library_defaults():
    o = stereo.DisparityOptions(method="sgbm", num_disparities=64, sgbm={"block_size": 3})
    assert (o.method, o.num_disparities, o.sgbm.block_size) == ("sgbm", 64, 3)
    assert o.bm.block_size == 11 and o.sgbm.p1_per_pixel == 8  # untouched defaults
    assert "num_disparities=64" in repr(o) and "SemiGlobalOptions(block_size=3" in repr(o)
    o.bm = {"block_size": 7}
    assert o.bm.block_size == 7
    assert stereo.StereoOptions(points={"beams": 64}).points.beams == 64
    with pytest.raises(TypeError, match="unexpected keyword argument 'block'"):
        stereo.DisparityOptions(block=5)
    with pytest.raises(ValueError, match="method: unknown|bm|sgbm"):
        stereo.DisparityOptions(method="census")
    left, right = textured_pair()
    with pytest.raises(ValueError, match="block_size"):
        stereo.disparity(left, right, bm={"block_size": 4})
    with pytest.raises(ValueError, match="outputs: unknown"):
        stereo.encode(left, right, CALIB, outputs=("lidar",))


@pytest.mark.parametrize("image, message", [
    (np.zeros((8, 8, 3)), r"left: expected a uint8 array of shape \(H, W, 3\).*got float64 array"),
    (np.zeros((8, 8, 4), dtype=np.uint8), r"got uint8 array of shape \(8, 8, 4\)"),
    (np.zeros((8,), dtype=np.uint8), r"got uint8 array of shape \(8,\)"),
    ([[1, 2], [3, 4]], r"left: expected a uint8 array.*got list"),
    (np.zeros((0, 8, 3), dtype=np.uint8), "the image is empty"),
])
def test_bad_images_raise_value_errors(image, message):
    right = np.zeros((8, 8, 3), dtype=np.uint8)
    with pytest.raises(ValueError, match=message):
        stereo.disparity(image, right)


def test_more_bad_input_raises_value_errors():
    left, right = textured_pair()
    with pytest.raises(ValueError, match="left and right differ in size"):
        stereo.disparity(left, right[:, :-4])
    with pytest.raises(ValueError, match="does not fit"):
        stereo.disparity(left[:6, :6], right[:6, :6])
    with pytest.raises(ValueError, match=r"disparity: expected an array of shape \(H, W\)"):
        stereo.depth_from_disparity(np.zeros((4, 4, 2)), CALIB)
    with pytest.raises(ValueError, match="disparity: expected numbers"):
        stereo.depth_from_disparity(np.array([["a"]]), CALIB)
    with pytest.raises(ValueError, match="focal length"):
        stereo.depth_from_disparity(np.ones((4, 4)), kitti.Calibration())
    with pytest.raises(ValueError, match=r"height_code: expected a uint16 array"):
        stereo.pack_rgbh(left, np.zeros(left.shape[:2], dtype=np.int32))
    with pytest.raises(ValueError, match="bgr and height_code differ in size"):
        stereo.pack_rgbh(left, np.zeros((3, 3), dtype=np.uint16))
    with pytest.raises(ValueError, match="ground: expected None or a dict"):
        stereo.height_from_disparity(np.ones((4, 4)), CALIB, ground=1.5)
    with pytest.raises(ValueError, match="layout: 'rgb' is not an RGB-H layout"):
        stereo.rgbh_planar(left, "rgb")
    with pytest.raises(TypeError):
        stereo.depth_from_disparity(np.ones((4, 4)), "calib")
