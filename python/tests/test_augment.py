"""``mmbm.augment``: the homographies carry a point to its blurred place, the
dtype and shape round-trip, batches draw one motion per seed, bad inputs are
clear errors."""

import numpy as np
import pytest

import mmbm


def dot(h=48, w=64, x=30, y=20):
    img = np.zeros((h, w, 3), np.float32)
    img[y - 1 : y + 1, x - 1 : x + 1] = 1.0
    return img


def apply(hm, x, y):
    p = hm @ np.array([x, y, 1.0])
    return p[:2] / p[2]


def centroid(img):
    g = img[:, :, 1].astype(np.float64)
    ys, xs = np.mgrid[0 : g.shape[0], 0 : g.shape[1]] + 0.5
    return (g * xs).sum() / g.sum(), (g * ys).sum() / g.sum()


@pytest.mark.parametrize("centre", [False, True])
def test_homographies_follow_the_dot(centre):
    out = mmbm.augment(dot(), motion={"omega": [0.0, 0.9, 0.2]}, exposure=0.03, centre=centre, return_maps=True)
    hs = out["homographies"]
    assert hs.shape == (3, 3, 3)
    start, mid, end = (apply(hs[k], 30.0, 20.0) for k in range(3))
    assert np.hypot(*(end - start)) > 10.0
    np.testing.assert_allclose(centroid(out["image"]), mid, atol=0.2)
    if centre:
        np.testing.assert_allclose(mid, [30.0, 20.0], atol=1e-3)
    else:
        np.testing.assert_allclose(start, [30.0, 20.0], atol=1e-9)
    assert out["maps"]["path_px"].shape == (48, 64)
    assert out["motion"] == "twist"


def test_uint8_and_gray_images_round_trip():
    rng = np.random.default_rng(1)
    u8 = rng.integers(0, 256, (24, 32, 3), dtype=np.uint8)
    out = mmbm.augment(u8, motion="sim:moderate", exposure=0.02, seed=3)
    assert out["image"].dtype == np.uint8 and out["image"].shape == u8.shape
    assert out["motion"].startswith("sim:moderate@")
    # Without motion the image comes back as given (never resampled).
    lin = rng.random((24, 32, 3)).astype(np.float32)
    still = mmbm.augment(lin, motion={"omega": [0, 0, 0]}, exposure=0.02)["image"]
    np.testing.assert_array_equal(still, lin)
    gray = mmbm.augment(u8[:, :, 0], motion="shake", exposure=0.02, seed=3)
    assert gray["image"].shape == (24, 32)


def test_a_batch_draws_one_motion_per_seed():
    imgs = np.stack([dot(24, 32, 16, 12)] * 3)
    b = mmbm.augment_batch(imgs, motion="shake", exposure=0.02, seed=10)
    assert b["image"].shape == (3, 24, 32, 3) and b["homographies"].shape == (3, 3, 3, 3)
    assert len(set(b["motion"])) == 3
    one = mmbm.augment(imgs[1], motion="shake", exposure=0.02, seed=11)
    np.testing.assert_array_equal(one["image"], b["image"][1])
    with pytest.raises(ValueError, match="seeds"):
        mmbm.augment_batch(imgs, seeds=[1, 2])


def test_bad_inputs_are_clear_errors():
    with pytest.raises(ValueError, match="shape"):
        mmbm.augment(np.zeros((4, 4, 2), np.float32))
    with pytest.raises(ValueError, match="motion 'wobble'"):
        mmbm.augment(dot(), motion="wobble")
    with pytest.raises(ValueError, match="not finite"):
        bad = dot()
        bad[3, 4, 0] = np.nan
        mmbm.augment(bad, motion="shake")
    with pytest.raises(ValueError, match="exposure"):
        mmbm.augment(dot(), motion="shake", exposure=0.0)
    with pytest.raises(ValueError, match="640 x 480 px where the image is 64 x 48"):
        mmbm.augment(dot(), motion="shake", camera=mmbm.Camera())


def test_sharp_names_the_reference_instant():
    """``sharp``: the image is the frame at exposure start, middle or end (that
    homography is the identity); ``centre=True`` is ``sharp="mid"``."""
    kw = dict(motion={"omega": [0.0, 0.9, 0.2]}, exposure=0.03)
    for k, at in enumerate(["start", "mid", "end"]):
        out = mmbm.augment(dot(), sharp=at, **kw)
        np.testing.assert_allclose(out["homographies"][k], np.eye(3), atol=1e-9)
        assert np.abs(out["homographies"][2 - k] - np.eye(3)).max() > 1e-3 or k == 1
    mid = mmbm.augment(dot(), sharp="mid", **kw)
    alias = mmbm.augment(dot(), centre=True, **kw)
    np.testing.assert_array_equal(mid["image"], alias["image"])
    # The default is the GoPro / REDS convention, as mmbm dataset's.
    np.testing.assert_array_equal(mid["image"], mmbm.augment(dot(), **kw)["image"])
    start = mmbm.augment(dot(), sharp="start", **kw)
    np.testing.assert_array_equal(start["image"], mmbm.augment(dot(), centre=False, **kw)["image"])
    with pytest.raises(ValueError, match="contradicts"):
        mmbm.augment(dot(), centre=True, sharp="end", **kw)
    with pytest.raises(ValueError, match="middle"):
        mmbm.augment(dot(), sharp="middle", **kw)
