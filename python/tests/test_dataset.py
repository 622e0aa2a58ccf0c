"""``mmbm.BlurDataset`` (the command's items, made on the fly, split over
workers) and the command's WebDataset shards read by the ``webdataset``
package and by the standard library's tarfile."""

import hashlib
import io
import json
import os
import subprocess
import tarfile
from pathlib import Path

import numpy as np
import pytest

import mmbm
import mmbm.dataset

ROOT = Path(__file__).resolve().parents[2]
BIN = os.environ.get("MMBM_BIN", str(ROOT / "target" / "release" / "mmbm"))
FILES = ["blurred.exr", "blurred.png", "sharp.exr", "sharp.png", "flow.exr", "maps.exr"]


def config_text(count: int) -> str:
    tex = (ROOT / "assets" / "textures").as_posix()
    return (
        f'count = {count}\nseed = 7\ntextures = "{tex}"\n'
        'motion = ["sim:moderate", "sim:fast"]\nresolution = [32, 24]\n'
    )


@pytest.fixture(scope="module")
def cli_set(tmp_path_factory):
    """A 5-item set made by the command, packed as WebDataset in 2+ shards."""
    d = tmp_path_factory.mktemp("ds")
    cfg = d / "ds.toml"
    cfg.write_text(config_text(5))
    out = d / "data"
    r = subprocess.run(
        [BIN, "dataset", "--config", str(cfg), "--out", str(out), "--format", "webdataset",
         "--shard-bytes", "65536", "--quiet"],
        capture_output=True, text=True,
    )
    assert r.returncode == 0, r.stderr
    return cfg, out


def sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_items_are_the_commands_byte_for_byte(cli_set, tmp_path):
    cfg, out = cli_set
    ds = mmbm.BlurDataset(cfg, cache_dir=tmp_path)
    assert len(ds) == 5
    assert ds.fingerprint == json.loads((out / "dataset.json").read_text())["fingerprint"]
    for i in (0, 3):
        item = ds.item(i)
        assert item["key"] == f"{i:08d}"
        for f in FILES + ["item.json"]:
            assert sha(Path(item["dir"]) / f) == sha(out / "items" / f"{i:08d}" / f), f
        # The arrays are the files' contents.
        exr = mmbm.read_exr(out / "items" / f"{i:08d}" / "maps.exr")
        np.testing.assert_array_equal(item["maps"]["path_px"], exr["path_px"])
        assert item["blurred"].shape == (24, 32, 3) and item["blurred"].dtype == np.float32
        line = json.loads((out / "items" / f"{i:08d}" / "item.json").read_text())
        assert item["params"] == line["params"]
        assert item["measures"]["blur_path_px"] == line["blur_path_px"]
    # Without a cache, the same arrays from a temporary folder.
    plain = mmbm.BlurDataset(toml=config_text(5)).item(3)
    assert plain["dir"] is None
    np.testing.assert_array_equal(plain["blurred"], ds.item(3)["blurred"])


def test_four_workers_make_each_item_once(monkeypatch):
    ds = mmbm.BlurDataset(toml=config_text(10), start=1, stop=10)
    seen = []
    for k in range(4):
        got = list(ds.indices((k, 4)))
        assert all(i % 4 == (1 + k) % 4 for i in got)
        seen += got
    assert sorted(seen) == list(range(1, 10)) and len(seen) == len(set(seen))
    # Iteration inside a worker (torch's get_worker_info, stood in for here).
    monkeypatch.setattr(mmbm.dataset, "_worker_info", lambda: (2, 4))
    small = mmbm.BlurDataset(toml=config_text(10), start=0, stop=7)
    assert [it["index"] for it in small] == [2, 6]
    monkeypatch.setattr(mmbm.dataset, "_worker_info", lambda: (5, 4))
    with pytest.raises(ValueError, match="worker 5 of 4"):
        list(small)


def test_bad_configurations_are_clear_errors(tmp_path):
    with pytest.raises(ValueError, match="count"):
        mmbm.BlurDataset(toml="count = 0\n")
    with pytest.raises(ValueError, match="toml"):
        mmbm.BlurDataset(toml="count = [\n")
    with pytest.raises(OSError):
        mmbm.BlurDataset(tmp_path / "missing.toml")
    with pytest.raises(ValueError, match="0..3"):
        mmbm.BlurDataset(toml=config_text(3), stop=4)
    with pytest.raises(IndexError):
        mmbm.BlurDataset(toml=config_text(3)).item(3)


def test_webdataset_package_reads_the_shards(cli_set):
    import webdataset as wds

    _, out = cli_set
    index = json.loads((out / "webdataset" / "index.json").read_text())
    assert index["complete"] and len(index["shards"]) >= 2
    urls = [str(out / "webdataset" / s["name"]) for s in index["shards"]]
    samples = list(wds.WebDataset(urls, shardshuffle=False))
    assert [s["__key__"] for s in samples] == [f"{i:08d}" for i in range(5)]
    for s in samples:
        d = out / "items" / s["__key__"]
        assert s["json"] == (d / "item.json").read_bytes()
        for f in FILES:
            assert s[f] == (d / f).read_bytes(), f
    # The standard library's reader agrees: members in order, sizes as listed.
    for s in index["shards"]:
        p = out / "webdataset" / s["name"]
        assert p.stat().st_size == s["bytes"] and sha(p) == s["sha256"]
        with tarfile.open(p) as t:
            names = t.getnames()
            assert all(m.mtime == 0 and m.uid == 0 for m in t.getmembers())
        keys = sorted({n.split(".", 1)[0] for n in names})
        assert keys == [f"{i:08d}" for i in range(s["first"], s["first"] + s["items"])]
