"""Issue 37: the command's WebDataset shards load in Hugging Face ``datasets``
(``load_dataset("webdataset", ...)``, in memory and streaming) and in the
``webdataset`` package, every sample read; every number in a sample's JSON
fits int64 (seeds are decimal strings); and ``BlurDataset`` works with the
defaults from a directory that is not the repository (built-in textures).

Nothing here is skipped: without ``datasets`` (or Pillow, which it needs for
the PNG members), the imports fail and so do the tests."""

import hashlib
import json
import os
import subprocess
from pathlib import Path

os.environ.setdefault("HF_DATASETS_OFFLINE", "1")  # everything is local

import datasets  # noqa: E402
import numpy as np  # noqa: E402
import PIL.Image  # noqa: E402,F401  (datasets decodes the PNG members with it)
import pytest  # noqa: E402
import webdataset as wds  # noqa: E402

import mmbm  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
BIN = os.environ.get("MMBM_BIN", str(ROOT / "target" / "release" / "mmbm"))
FILES = ["blurred.exr", "blurred.png", "sharp.exr", "sharp.png", "flow.exr", "maps.exr"]
INT64_MAX = 2**63 - 1
COUNT = 6


def numbers_fit_int64(v, at="json"):
    """Every integer in ``v`` (recursively) within int64."""
    if isinstance(v, bool) or v is None or isinstance(v, (str, float)):
        return
    if isinstance(v, int):
        assert -(2**63) <= v <= INT64_MAX, f"{at}: {v} does not fit int64"
    elif isinstance(v, list):
        for i, x in enumerate(v):
            numbers_fit_int64(x, f"{at}[{i}]")
    elif isinstance(v, dict):
        for k, x in v.items():
            numbers_fit_int64(x, f"{at}.{k}")
    else:
        raise AssertionError(f"{at}: unexpected {type(v)}")


@pytest.fixture(scope="module")
def shards(tmp_path_factory):
    """6 items made by the command from a folder outside the repository
    (a relative config, the built-in textures), packed into 2+ shards."""
    d = tmp_path_factory.mktemp("hf")
    (d / "ds.toml").write_text(
        f'count = {COUNT}\nresolution = [32, 24]\nmotion = ["sim:moderate", "sim:fast"]\n'
    )
    r = subprocess.run(
        [BIN, "dataset", "--config", "ds.toml", "--out", "data", "--format", "webdataset",
         "--shard-bytes", "65536", "--quiet"],
        capture_output=True, text=True, cwd=d,
    )
    assert r.returncode == 0, r.stderr
    out = d / "data"
    lines = [json.loads(t) for t in (out / "manifest.jsonl").read_text().splitlines()]
    assert len(lines) == COUNT
    # The case that broke Arrow: a seed above 2^63 - 1 (3 of these 6).
    seeds = [int(line["params"]["seed"]) for line in lines]
    assert any(s > INT64_MAX for s in seeds), seeds
    index = json.loads((out / "webdataset" / "index.json").read_text())
    urls = [str(out / "webdataset" / s["name"]) for s in index["shards"]]
    assert len(urls) >= 2
    return out, urls, lines


def check_sample(out, lines, key, meta, exr_bytes):
    i = int(key)
    assert meta == lines[i], key
    assert meta["params"]["sharp"] == "mid"
    assert isinstance(meta["params"]["seed"], str)
    numbers_fit_int64(meta)
    assert exr_bytes == (out / "items" / key / "blurred.exr").read_bytes()


def test_manifest_and_item_json_numbers_fit_int64(shards):
    out, _, lines = shards
    for line in lines:
        numbers_fit_int64(line)
        item = json.loads((out / line["dir"] / "item.json").read_text())
        assert item == line


def test_hugging_face_load_dataset_reads_every_sample(shards, tmp_path):
    out, urls, lines = shards
    ds = datasets.load_dataset(
        "webdataset", data_files=urls, split="train", cache_dir=str(tmp_path / "cache")
    )
    assert ds.num_rows == COUNT
    keys = []
    for s in ds:
        keys.append(s["__key__"])
        check_sample(out, lines, s["__key__"], s["json"], s["blurred.exr"])
        assert s["sharp.png"].size == (32, 24)
        png = np.asarray(s["blurred.png"].convert("RGB"))
        assert png.shape == (24, 32, 3)
    assert sorted(keys) == [f"{i:08d}" for i in range(COUNT)]


def test_hugging_face_streaming_reads_every_sample(shards):
    out, urls, lines = shards
    ds = datasets.load_dataset("webdataset", data_files=urls, split="train", streaming=True)
    keys = []
    for s in ds:
        keys.append(s["__key__"])
        check_sample(out, lines, s["__key__"], s["json"], s["blurred.exr"])
        for f in ("flow.exr", "maps.exr", "sharp.exr"):
            assert s[f] == (out / "items" / s["__key__"] / f).read_bytes(), f
    assert keys == [f"{i:08d}" for i in range(COUNT)]
    # As Arrow too (where a seed above 2^63 - 1 raised OverflowError).
    tables = list(ds.with_format("arrow"))
    assert sum(t.num_rows for t in tables) == COUNT
    seeds = [str(r["params"]["seed"]) for t in tables for r in t.column("json").to_pylist()]
    assert seeds == [line["params"]["seed"] for line in lines]


def test_webdataset_package_reads_every_sample(shards):
    out, urls, lines = shards
    keys = []
    for s in wds.WebDataset(urls, shardshuffle=False):
        keys.append(s["__key__"])
        check_sample(out, lines, s["__key__"], json.loads(s["json"]), s["blurred.exr"])
        for f in FILES:
            assert s[f] == (out / "items" / s["__key__"] / f).read_bytes(), f
    assert keys == [f"{i:08d}" for i in range(COUNT)]


def sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_blur_dataset_defaults_work_outside_the_repository(tmp_path, monkeypatch):
    """The wheel ships no texture files: the defaults use the built-in ones,
    and item 0 is the command's default item 0, file for file."""
    work = tmp_path / "elsewhere"
    work.mkdir()
    monkeypatch.chdir(work)
    ds = mmbm.BlurDataset(cache_dir=tmp_path / "cache")
    assert len(ds) == 100
    item = ds.item(0)
    assert item["params"]["sharp"] == "mid"
    assert item["blurred"].shape == (480, 640, 3)
    r = subprocess.run(
        [BIN, "dataset", "--out", "cli", "--count", "1", "--quiet"],
        capture_output=True, text=True, cwd=work,
    )
    assert r.returncode == 0, r.stderr
    for f in FILES:
        assert sha(Path(item["dir"]) / f) == sha(work / "cli" / "items" / "00000000" / f), f
    cli = json.loads((work / "cli" / "items" / "00000000" / "item.json").read_text())
    assert cli["params"] == item["params"]
