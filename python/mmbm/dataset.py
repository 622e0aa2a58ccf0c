"""Blur datasets for training: ``BlurDataset``, items made on the fly.

``BlurDataset(config)`` yields the items of a ``mmbm dataset`` configuration
(a TOML file, TOML text, or the defaults), each made by the same code as
the command and so with the same bytes: ``item["dir"]`` holds the item's
files, and the arrays are read from them. It is a PyTorch
``IterableDataset`` when torch is installed (torch is not needed
otherwise): in a ``DataLoader`` with ``num_workers=N``, worker ``k`` makes
the items ``i`` with ``i % N == k`` (from ``get_worker_info``), so each item
is made once. Seeds are per item (the configuration's seed and the item's
index, as in the command), not per worker: the items do not depend on the
number of workers.

>>> ds = BlurDataset(toml='count = 2\\nresolution = [32, 24]')  # doctest: +SKIP
>>> item = next(iter(ds))                                      # doctest: +SKIP
>>> item["blurred"].shape, item["maps"]["path_px"].shape       # doctest: +SKIP
((24, 32, 3), (24, 32))
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import socket
import tempfile
from typing import Any, Callable, Dict, Iterator, Optional, Tuple, Union

import numpy as np

from . import _mmbm

PathLike = Union[str, "os.PathLike[str]"]

try:  # A torch IterableDataset where torch is installed; a plain class otherwise.
    from torch.utils.data import IterableDataset as _Base  # type: ignore
except ImportError:  # pragma: no cover - depends on the environment

    class _Base:  # type: ignore[no-redef]
        pass


def _worker_info() -> Tuple[int, int]:
    """(worker id, number of workers) from torch's ``get_worker_info``; (0, 1)
    outside a DataLoader worker or without torch."""
    try:
        from torch.utils.data import get_worker_info  # type: ignore
    except ImportError:
        return 0, 1
    info = get_worker_info()
    if info is None:
        return 0, 1
    return int(info.id), int(info.num_workers)


def _rgb(exr: Dict[str, np.ndarray]) -> np.ndarray:
    return np.stack([exr["R"], exr["G"], exr["B"]], axis=-1)


class BlurDataset(_Base):
    """The items ``start..stop`` of a dataset configuration, made on the fly.

    ``config``: a TOML file; or ``toml``: TOML text; neither: the defaults
    (``mmbm dataset --print-config``). ``cache_dir``: keep each item's files
    in ``cache_dir/NNNNNNNN/`` (and reuse a complete one; processes may
    share one cache: each makes an item in a folder of its own and renames
    it into place, see ``_make_cached``); default: a temporary directory per
    item, removed once read. Each item is a dict:
    ``index``, ``key`` (8 digits, as in the WebDataset shards), ``params``
    and ``measures`` (the manifest line's), ``blurred`` and ``sharp``
    ((H, W, 3) float32, linear), ``flow`` (``u``, ``v``: px/s at exposure
    start) and ``maps`` (``path_px``, ``disp_px``, ``speed_px_s``), and
    ``dir`` (the item's folder when ``cache_dir`` is set, else None).
    ``transform``: a function applied to each item that iteration and
    indexing (``ds[i]``, ``i`` counted from ``start``) return (e.g. one
    calling ``mmbm.augment`` on ``item["sharp"]``); ``item(index)`` returns
    the item as made.
    """

    def __init__(
        self,
        config: Optional[PathLike] = None,
        *,
        toml: Optional[str] = None,
        start: int = 0,
        stop: Optional[int] = None,
        cache_dir: Optional[PathLike] = None,
        transform: Optional[Callable[[Dict[str, Any]], Any]] = None,
    ) -> None:
        self.transform = transform
        self._maker = _mmbm.DatasetMaker(
            path=None if config is None else os.fspath(config), toml=toml
        )
        n = self._maker.count
        stop = n if stop is None else stop
        if not (0 <= start <= stop <= n):
            raise ValueError(f"items {start}..{stop}: the dataset has items 0..{n}")
        self.start, self.stop = int(start), int(stop)
        self.cache_dir = None if cache_dir is None else os.fspath(cache_dir)

    @property
    def fingerprint(self) -> str:
        """The configuration's fingerprint (``DIR/dataset.json``'s)."""
        return self._maker.fingerprint

    def __len__(self) -> int:
        return self.stop - self.start

    def indices(self, worker: Optional[Tuple[int, int]] = None) -> range:
        """The item indices worker ``(id, count)`` makes (default: this
        process's, from torch's ``get_worker_info``)."""
        wid, nw = _worker_info() if worker is None else worker
        if not (0 <= wid < nw):
            raise ValueError(f"worker {wid} of {nw}")
        return range(self.start + wid, self.stop, nw)

    def item(self, index: int) -> Dict[str, Any]:
        """Item ``index`` (made now, or read from ``cache_dir``)."""
        if not (self.start <= index < self.stop):
            raise IndexError(f"item {index}: this dataset has items {self.start}..{self.stop}")
        if self.cache_dir is not None:
            d = os.path.join(self.cache_dir, f"{index:08d}")
            if not os.path.isfile(os.path.join(d, "item.json")):
                self._make_cached(index, d)
            with open(os.path.join(d, "item.json"), encoding="utf-8") as f:
                line = json.loads(f.read())
            if line.get("fingerprint") != self.fingerprint or line.get("index") != index:
                raise ValueError(
                    f"{d}: made with another configuration or index: use another cache_dir"
                )
            return self._read(index, line, d, keep=True)
        with tempfile.TemporaryDirectory(prefix="mmbm-item-") as d:
            line = json.loads(self._maker.make(index, d))
            return self._read(index, line, d, keep=False)

    def _make_cached(self, index: int, d: str) -> None:
        """Makes item ``index`` into the cache folder ``d``, safely beside other
        processes sharing the cache (DataLoader workers, distributed ranks).

        The item is made in a folder of this process's own
        (``NNNNNNNN.partial-<host>-<pid>-<random>``), then renamed to ``d`` in
        one step, so a reader sees either no folder or a complete one. When
        another process renamed its copy into place first, this one's is
        removed and theirs used (the same bytes: an item depends only on the
        configuration and its index). Only this process's own partial folder
        is ever removed: a killed process leaves its ``.partial-*`` folder,
        which no other process touches (remove it when nothing runs).
        """
        os.makedirs(self.cache_dir, exist_ok=True)
        tag = f"{socket.gethostname()}-{os.getpid()}-{secrets.token_hex(6)}"
        part = f"{d}.partial-{tag}"
        os.mkdir(part)
        try:
            self._maker.make(index, part)
            try:
                os.rename(part, d)
            except OSError:
                # Another process's complete copy is in place (a rename onto a
                # folder that is not empty fails): use it.
                if not os.path.isfile(os.path.join(d, "item.json")):
                    raise
        finally:
            if os.path.exists(part):
                shutil.rmtree(part, ignore_errors=True)

    @staticmethod
    def _read(index: int, line: Dict[str, Any], d: str, keep: bool) -> Dict[str, Any]:
        flow = _mmbm.read_exr(os.path.join(d, "flow.exr"))
        measures = {
            k: v
            for k, v in line.items()
            if k not in ("index", "dir", "fingerprint", "params", "files")
        }
        return {
            "index": index,
            "key": f"{index:08d}",
            "params": line["params"],
            "measures": measures,
            "blurred": _rgb(_mmbm.read_exr(os.path.join(d, "blurred.exr"))),
            "sharp": _rgb(_mmbm.read_exr(os.path.join(d, "sharp.exr"))),
            "flow": {"u": flow["flow.u"], "v": flow["flow.v"]},
            "maps": dict(_mmbm.read_exr(os.path.join(d, "maps.exr"))),
            "dir": d if keep else None,
        }

    def __getitem__(self, k: int) -> Any:
        """Item ``start + k``, through ``transform``."""
        if not 0 <= k < len(self):
            raise IndexError(f"item {k}: this dataset has {len(self)} items")
        it = self.item(self.start + k)
        return it if self.transform is None else self.transform(it)

    def __iter__(self) -> Iterator[Any]:
        for i in self.indices():
            yield self[i - self.start]
