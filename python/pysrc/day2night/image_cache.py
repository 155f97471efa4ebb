"""``DecodedImages``: the day images one process keeps decoded for ``NightPairs`` (and
``FreshPatches`` through it), least recently used out first, within a count and a byte
bound. No torch import."""

import operator
import os
from collections import OrderedDict

from ._native import read_dng

#: The default bound on the decoded planes kept per process: 4 GiB holds the experiment's
#: 60 training images of 12 MP (1.5 GB).
CACHE_BYTES = 4 << 30


def plane_bytes(meta):
    """Bytes of a decoded image's plane: width x height x samples x 2."""
    return int(meta["width"]) * int(meta["height"]) * int(meta.get("samples_per_pixel") or 1) * 2


class DecodedImages:
    """The decoded images of ``folder`` this process keeps: at most ``cache`` of them (None:
    no count bound) and at most ``cache_bytes`` of their planes; the image in use always
    stays. A pickle (a worker started by spawn) carries the bounds, not the images."""

    def __init__(self, folder, cache=None, cache_bytes=CACHE_BYTES):
        if cache is not None:
            cache = operator.index(cache)
            if cache < 1:
                raise ValueError(f"cache {cache}: keep at least 1 decoded image (None: no limit)")
        cache_bytes = operator.index(cache_bytes)
        if cache_bytes < 0:
            raise ValueError(f"cache_bytes {cache_bytes} must be at least 0")
        self.folder, self.count, self.bytes = folder, cache, cache_bytes
        self._entries = OrderedDict()  # name -> (raw, DefaultCrop, plane bytes)

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_entries"] = OrderedDict()
        return state

    def __len__(self):
        return len(self._entries)

    def names(self):
        """The names kept, least recently used first."""
        return list(self._entries)

    def _read(self, name):
        raw = read_dng(os.path.join(self.folder, name))
        meta = raw.meta
        return raw, tuple(meta["default_crop"]), plane_bytes(meta)

    def _held(self):
        return sum(e[2] for e in self._entries.values())

    def get(self, name):
        """(raw, DefaultCrop) of image ``name``, decoded now unless it is kept; then the
        least recently used others go beyond the bounds."""
        entry = self._entries.get(name)
        if entry is not None:
            self._entries.move_to_end(name)
            return entry[:2]
        entry = self._entries[name] = self._read(name)
        while len(self._entries) > 1 and (
                (self.count is not None and len(self._entries) > self.count)
                or self._held() > self.bytes):
            self._entries.popitem(last=False)
        return entry[:2]

    def add(self, name):
        """(raw, DefaultCrop) of image ``name`` if it is kept or fits beside those kept
        (the first always does), without dropping any; None when the bounds are full."""
        entry = self._entries.get(name)
        if entry is None:
            if self.count is not None and len(self._entries) >= self.count:
                return None
            entry = self._read(name)
            if self._entries and self._held() + entry[2] > self.bytes:
                return None
            self._entries[name] = entry
        return entry[:2]
