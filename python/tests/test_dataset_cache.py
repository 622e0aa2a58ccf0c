"""``mmbm.BlurDataset(cache_dir=...)`` shared by several processes at once, as
distributed-training ranks share a cache: no process fails, none removes
another's partial item, every cached item is complete and equal to the item
made alone, and no partial folder is left behind."""

import hashlib
import multiprocessing as mp
import os
from pathlib import Path

import mmbm

ROOT = Path(__file__).resolve().parents[2]
FILES = ["blurred.exr", "blurred.png", "sharp.exr", "sharp.png", "flow.exr", "maps.exr", "item.json"]
COUNT = 6
ROUNDS = 3


def config_text() -> str:
    tex = (ROOT / "assets" / "textures").as_posix()
    return (
        f'count = {COUNT}\nseed = 11\ntextures = "{tex}"\n'
        'motion = ["sim:moderate", "sim:fast"]\nresolution = [24, 16]\n'
    )


def digests(d: Path) -> dict:
    return {f: hashlib.sha256((d / f).read_bytes()).hexdigest() for f in FILES}


def worker(cache: str, start, results) -> None:
    """Reads every item of a fresh cache (all processes on the same item at
    the same moment), several rounds, each on a new cache folder."""
    try:
        ds = mmbm.BlurDataset(toml=config_text(), cache_dir=None)
        for r in range(ROUNDS):
            ds.cache_dir = os.path.join(cache, f"round{r}")
            for i in range(COUNT):
                start.wait(timeout=120)
                item = ds.item(i)
                assert item["index"] == i and item["blurred"].shape == (16, 24, 3)
        results.put((os.getpid(), "ok"))
    except BaseException as e:  # reported to the parent, which fails the test
        start.abort()  # the others stop waiting for this one
        results.put((os.getpid(), f"{type(e).__name__}: {e}"))


def test_three_processes_share_one_cache_dir(tmp_path):
    ctx = mp.get_context("spawn")
    n = 3
    start = ctx.Barrier(n)
    results = ctx.Queue()
    procs = [ctx.Process(target=worker, args=(str(tmp_path), start, results)) for _ in range(n)]
    for p in procs:
        p.start()
    got = [results.get(timeout=240) for _ in procs]
    for p in procs:
        p.join(timeout=60)
    failures = [g for g in got if g[1] != "ok"]
    assert not failures, failures
    # Every cached item complete and equal to the item made alone.
    alone = tmp_path / "alone"
    ref = mmbm.BlurDataset(toml=config_text(), cache_dir=alone)
    for i in range(COUNT):
        ref.item(i)
    for r in range(ROUNDS):
        cache = tmp_path / f"round{r}"
        names = sorted(os.listdir(cache))
        assert names == [f"{i:08d}" for i in range(COUNT)], names  # no partial left
        for i in range(COUNT):
            assert digests(cache / f"{i:08d}") == digests(alone / f"{i:08d}"), (r, i)


def test_a_partial_folder_of_another_process_is_left_alone(tmp_path):
    """A partial folder under another process's name (a rank making the item,
    or one killed mid-way) is neither read nor removed."""
    other = tmp_path / "00000001.partial-otherhost-1-abc"
    other.mkdir(parents=True)
    (other / "blurred.exr").write_bytes(b"half")
    ds = mmbm.BlurDataset(toml=config_text(), cache_dir=tmp_path)
    item = ds.item(1)
    assert item["dir"] == str(tmp_path / "00000001")
    assert (other / "blurred.exr").read_bytes() == b"half"
