"""File names made from scene ids and day-image names inside the run folder, kept within the
file system's limit of :data:`NAME_MAX` bytes per name (docs/experiment.md, "Run folder").

A file is written through a temporary name beside it (atomic.py: ``.<name>.<8 random
characters>.tmp``, :data:`TEMP_EXTRA` bytes more than the name). A scene id or a day image's
stem longer than its room (the limit less the temporary name's extra and the longest suffix
the run adds to it) is shortened to a stable name: its first bytes (whole UTF-8 characters)
and ``~`` and 16 hex digits of its SHA-256, so the same id always gives the same file, and two
ids that share their first bytes still give two files. A name within its room is unchanged
(a run folder of an earlier version resumes). The names the user sees (table.json, the page)
stay the ids themselves."""

import hashlib

NAME_MAX = 255
#: atomic.open_atomic's temporary name: "." + name + "." + 8 random characters + ".tmp".
TEMP_EXTRA = 1 + 1 + 8 + 4
#: The longest suffix after a scene id: "_clean_target.png" (report images; the cached pairs'
#: "_3200.in.npy" is shorter).
SCENE_SUFFIX_MAX = len("_clean_target.png")
#: The longest suffix after a day image's stem: "_3200.in.npy" (its cached pairs).
DAY_SUFFIX_MAX = len("_3200.in.npy")
SCENE_ROOM = NAME_MAX - TEMP_EXTRA - SCENE_SUFFIX_MAX
DAY_ROOM = NAME_MAX - TEMP_EXTRA - DAY_SUFFIX_MAX
_HASH = 16


def short(name, room):
    """``name`` when its UTF-8 form fits in ``room`` bytes, else its first bytes (whole
    characters) + "~" + 16 hex digits of its SHA-256 (``room`` bytes at most)."""
    raw = name.encode("utf-8")
    if len(raw) <= room:
        return name
    head = raw[: room - _HASH - 1].decode("utf-8", errors="ignore")
    return f"{head}~{hashlib.sha256(raw).hexdigest()[:_HASH]}"


def scene_stem(sid):
    """The file-name stem of the scene ``sid`` (its cached pairs, its report images)."""
    return short(sid, SCENE_ROOM)


def image_stem(sid, key):
    """The stem of a report image of scene ``sid`` and input ``key``:
    RUN/img/<task>/.../<stem>_{input,target,pred,de}.png."""
    return f"{scene_stem(sid)}_{key}"


def day_stem(name):
    """The file-name stem of the day image ``name`` (its path under --day: "/" as "__",
    without its extension) for its cached pairs."""
    return short(name.replace("/", "__").rsplit(".", 1)[0], DAY_ROOM)


def day_link(name):
    """The name of the link to the day image ``name`` (data/day-train: no temporary name)."""
    flat = name.replace("/", "__")
    stem, dot, ext = flat.rpartition(".")
    if not dot:
        return short(flat, NAME_MAX)
    return f"{short(stem, NAME_MAX - 1 - len(ext.encode('utf-8')))}.{ext}"
