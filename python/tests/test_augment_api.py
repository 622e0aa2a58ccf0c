"""``mmbm.augment`` as users of albumentations and kornia expect it: zero
motion returns the input bit for bit, random by default and reproducible with
a seed, ``p``, every shape (HW, HW1, HW3, HW4, NHWC, NCHW) and dtype, blur_px,
borders, fields, ``read_exr`` from bytes, ``BlurDataset(transform=)``, and the
pixel cap refused from the shape before any copy."""

import io
import os
import tarfile
from pathlib import Path

import numpy as np
import pytest

import mmbm

TEX = (Path(__file__).resolve().parents[2] / "assets" / "textures").as_posix()
DS = f'count = 2\nseed = 7\ntextures = "{TEX}"\nresolution = [32, 24]\n'
STILL = {"omega": [0.0, 0.0, 0.0]}
YAW = {"omega": [0.0, 0.7, 0.1]}  # about 20 px over 30 ms at 160 px wide


def noise(shape, dtype, seed=0):
    rng = np.random.default_rng(seed)
    if np.issubdtype(dtype, np.integer):
        return rng.integers(0, np.iinfo(dtype).max + 1, shape, dtype=dtype)
    return rng.random(shape).astype(dtype)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float16, np.float32, np.float64])
@pytest.mark.parametrize("shape", [(120, 160), (120, 160, 1), (120, 160, 3), (120, 160, 4)])
def test_zero_motion_returns_the_input_bit_for_bit(dtype, shape):
    img = noise(shape, dtype)
    for integrator in ("fast", "exact"):
        out = mmbm.augment(img, motion=STILL, integrator=integrator)
        assert out["image"].dtype == img.dtype and out["image"].shape == img.shape
        np.testing.assert_array_equal(out["image"], img)
        assert out["samples"] == 0 and out["applied"]


def test_seed_none_differs_and_a_seed_reproduces():
    img = noise((60, 80, 3), np.uint8)
    a, b = mmbm.augment(img), mmbm.augment(img)
    assert a["seed"] != b["seed"]
    assert not np.array_equal(a["image"], b["image"]) or a["motion"] != b["motion"]
    c, d = mmbm.augment(img, seed=5), mmbm.augment(img, seed=5)
    np.testing.assert_array_equal(c["image"], d["image"])
    assert c["motion"] == d["motion"]
    again = mmbm.augment(img, seed=a["seed"])
    np.testing.assert_array_equal(again["image"], a["image"])


def test_p_zero_returns_the_input_and_p_is_drawn_per_seed():
    img = noise((40, 50, 3), np.float32)
    out = mmbm.augment(img, p=0.0, seed=1)
    assert out["image"] is img and not out["applied"] and out["motion"] == "none"
    applied = [mmbm.augment(img, p=0.5, seed=s, motion=STILL)["applied"] for s in range(40)]
    assert 5 < sum(applied) < 35
    with pytest.raises(ValueError, match="p: 1.5"):
        mmbm.augment(img, p=1.5)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float16, np.float32, np.float64])
@pytest.mark.parametrize("shape", [(48, 64), (48, 64, 1), (48, 64, 3), (48, 64, 4)])
def test_every_shape_and_dtype_is_blurred_in_kind(dtype, shape):
    img = noise(shape, dtype)
    out = mmbm.augment(img, motion=YAW, seed=1)
    y = out["image"]
    assert y.dtype == img.dtype and y.shape == img.shape
    assert out["samples"] > 1 and not np.array_equal(y, img)
    # Blur lowers the contrast of noise (colour channels; alpha too).
    assert y.astype(np.float64).std() < 0.8 * img.astype(np.float64).std()


def test_alpha_is_blurred_as_coverage_with_premultiplied_colour():
    img = np.zeros((40, 60, 4), np.float32)
    img[:, 20:40] = [1.0, 0.0, 0.0, 1.0]  # an opaque red band on transparent black
    out = mmbm.augment(img, motion=YAW, seed=0, centre=True)["image"]
    edge = out[:, :, 3]
    assert ((edge > 0.05) & (edge < 0.95)).any()
    visible = edge > 0.01
    # Where any of the band shows, its colour is pure red, not darkened.
    np.testing.assert_allclose(out[visible][:, 0], 1.0, atol=1e-4)
    np.testing.assert_allclose(out[visible][:, 1:3], 0.0, atol=1e-6)


@pytest.mark.parametrize("layout", ["NHWC", "NCHW"])
def test_batches_in_either_layout_are_the_images_one_by_one(layout):
    imgs = noise((4, 40, 56, 3), np.uint8)
    x = imgs if layout == "NHWC" else np.ascontiguousarray(imgs.transpose(0, 3, 1, 2))
    b = mmbm.augment_batch(x, motion="shake", seed=10)
    b2 = mmbm.augment_batch(x, motion="shake", seed=10, layout=layout)
    assert b["image"].shape == x.shape and b["image"].dtype == np.uint8
    np.testing.assert_array_equal(b["image"], b2["image"])
    assert len(set(b["motion"])) == 4 and b["seed"] == [10, 11, 12, 13]
    for k in range(4):
        one = mmbm.augment(imgs[k], motion="shake", seed=10 + k)
        got = b["image"][k] if layout == "NHWC" else b["image"][k].transpose(1, 2, 0)
        np.testing.assert_array_equal(got, one["image"])
    gray = mmbm.augment_batch(imgs[:, :, :, 0], motion=STILL)
    np.testing.assert_array_equal(gray["image"], imgs[:, :, :, 0])
    with pytest.raises(ValueError, match="layout"):
        mmbm.augment_batch(np.zeros((2, 5, 6, 7), np.float32))


def test_blur_px_is_the_mean_path():
    img = noise((96, 128, 3), np.float32)
    for target in (5.0, 20.0):
        out = mmbm.augment(img, motion="shake", seed=3, blur_px=target, centre=True, return_maps=True)
        assert abs(out["maps"]["path_px"].mean() / target - 1.0) < 0.03


def test_border_modes():
    grey = np.full((48, 64, 3), 0.5, np.float32)
    far = {"omega": [0.0, 1.0, 0.0]}
    for border in ("reflect", "replicate"):
        out = mmbm.augment(grey, motion=far, border=border, seed=0)["image"]
        np.testing.assert_allclose(out, 0.5, atol=1e-5)
    const = mmbm.augment(grey, motion=far, border="constant", background=(0, 0, 0), seed=0)["image"]
    assert const.min() < 0.3
    with pytest.raises(ValueError, match="border"):
        mmbm.augment(grey, motion=far, border="wrap")


def test_fields_are_returned_and_agree_with_the_homographies():
    img = noise((48, 64, 3), np.float32)
    out = mmbm.augment(img, motion=YAW, seed=0, return_fields=True, sharp="start")
    f = out["fields"]
    assert f.shape == (3, 48, 64, 2) and f.dtype == np.float32
    np.testing.assert_allclose(f[0], 0.0, atol=1e-4)  # exposure start is the reference
    # Pixel (i, j) sees image point q at the end; H_end carries q back to it.
    i, j = 40, 30
    q = np.array([i + 0.5 + f[2, j, i, 0], j + 0.5 + f[2, j, i, 1], 1.0])
    p = out["homographies"][2] @ q
    np.testing.assert_allclose(p[:2] / p[2], [i + 0.5, j + 0.5], atol=1e-3)
    assert np.abs(f[2]).max() > 5.0
    assert "fields" not in mmbm.augment(img, motion=YAW, seed=0)


def test_pixel_cap_is_refused_from_the_shape_before_any_copy():
    # 2^26 + 1 px of float64 would be 1.6 GB as RGB: a broadcast view costs nothing.
    huge = np.broadcast_to(np.float64(0.5), (8193, 8192, 3))
    with pytest.raises(ValueError, match="at most 67108864 px"):
        mmbm.augment(huge)
    with pytest.raises(ValueError, match="at most 67108864 px"):
        mmbm.augment_batch(np.broadcast_to(np.uint8(1), (2, 3, 8193, 8192)), layout="NCHW")


def test_read_exr_from_bytes(tmp_path):
    # An item's maps, written by the dataset maker.
    mmbm.BlurDataset(toml=DS, cache_dir=tmp_path).item(0)
    out = tmp_path / "00000000" / "maps.exr"
    by_path = mmbm.read_exr(out)
    by_bytes = mmbm.read_exr(out.read_bytes())
    assert by_path.keys() == by_bytes.keys() and "path_px" in by_bytes
    for k in by_path:
        np.testing.assert_array_equal(by_path[k], by_bytes[k])
    # A WebDataset-style tar member's bytes.
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w") as tar:
        tar.add(out, arcname="00000000.maps.exr")
    buf.seek(0)
    with tarfile.open(fileobj=buf) as tar:
        data = tar.extractfile("00000000.maps.exr").read()
    np.testing.assert_array_equal(mmbm.read_exr(data)["path_px"], by_path["path_px"])
    with pytest.raises(ValueError, match="EXR bytes"):
        mmbm.read_exr(b"not an exr file")


def test_blur_dataset_applies_the_transform():
    seen = []

    def t(item):
        seen.append(item["index"])
        return mmbm.augment(item["sharp"], motion=STILL)["image"], item["index"]

    ds = mmbm.BlurDataset(toml=DS, transform=t)
    got = list(ds)
    assert [i for _, i in got] == [0, 1] and seen == [0, 1]
    assert got[0][0].shape == (24, 32, 3)
    np.testing.assert_array_equal(ds[1][0], ds.item(1)["sharp"])
    assert "sharp" in ds.item(0)


def test_maps_only_when_asked_for():
    """The blur maps cost more than the fast blur: returned (and computed)
    only with ``return_maps``; the image is the same either way."""
    img = noise((48, 64, 3), np.float32)
    plain = mmbm.augment(img, motion=YAW, seed=2)
    assert "maps" not in plain
    with_maps = mmbm.augment(img, motion=YAW, seed=2, return_maps=True)
    np.testing.assert_array_equal(plain["image"], with_maps["image"])
    assert with_maps["maps"]["path_px"].shape == (48, 64)
    assert with_maps["maps"]["path_px"].mean() > 5.0
    b = mmbm.augment_batch(np.stack([img, img]), seed=2, motion=YAW, return_maps=True)
    assert b["maps"]["path_px"].shape == (2, 48, 64)
    assert "maps" not in mmbm.augment_batch(np.stack([img, img]), seed=2, motion=YAW)


def test_backend_choice_and_a_bad_value():
    # bulk (default) is a hardware GPU or the CPU; gpu is any adapter: both
    # compute the CPU's formula (within 1e-4 linear, tests/augment_gpu.rs).
    img = noise((48, 64, 3), np.float32)
    cpu = mmbm.augment(img, motion=YAW, seed=1, backend="cpu")["image"]
    bulk = mmbm.augment(img, motion=YAW, seed=1)["image"]
    np.testing.assert_allclose(bulk, cpu, atol=1e-4, rtol=0)
    batch = mmbm.augment_batch(img[None], seed=1, motion=YAW, backend="cpu")["image"][0]
    np.testing.assert_array_equal(batch, cpu)
    with pytest.raises(ValueError, match="backend"):
        mmbm.augment(img, motion=YAW, seed=1, backend="cuda")
    try:
        gpu = mmbm.augment(img, motion=YAW, seed=1, backend="gpu")["image"]
    except Exception as e:  # no adapter here
        if os.environ.get("MMBM_REQUIRE_GPU") == "1":
            raise
        pytest.skip(f"no GPU adapter: {e}")
    np.testing.assert_allclose(gpu, cpu, atol=1e-4, rtol=0)
