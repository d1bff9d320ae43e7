"""Maps as map_server files: a binary PGM image and a YAML description (``mode: trinary``).

Saving follows nav2's ``map_saver`` (occupancy >= 65 black, <= 20 white 254, otherwise and unknown grey 205; the
image's top row is the grid's last row). The YAML says ``free_thresh: 0.196`` (as ROS 1's map_saver) so grey 205
loads back as unknown in every map_server, and loading follows the map_server rule: ``p = (255 - pixel) / 255``,
occupied if ``p > occupied_thresh``, free if ``p < free_thresh``, else unknown.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

OCCUPIED_THRESH = 0.65
FREE_THRESH = 0.196
_OCC_INT = round(OCCUPIED_THRESH * 100)
_FREE_INT = round(FREE_THRESH * 100)


@dataclass(frozen=True)
class MapFile:
    """A loaded map.

    Attributes:
        data: (height, width) int8 occupancy, row 0 at the origin (``OccupancyGrid`` layout): -1, 0 or 100.
        resolution: Cell size [m].
        origin: Map-frame (x, y, yaw) of the lower-left cell's corner [m, m, rad].
        yaml: The YAML file read.
    """

    data: npt.NDArray[np.int8]
    resolution: float
    origin: tuple[float, float, float]
    yaml: Path


def trinary(data: npt.NDArray[np.int8]) -> npt.NDArray[np.int8]:
    """What saving then loading makes of ``data``: 100 where >= 65, 0 where in [0, 20], -1 elsewhere."""
    out = np.full(data.shape, -1, np.int8)
    out[(data >= 0) & (data <= _FREE_INT)] = 0
    out[(data >= _OCC_INT) & (data <= 100)] = 100
    return out


def save_map(path: str | Path, data: npt.NDArray[np.int8], resolution: float,
             origin: tuple[float, float]) -> Path:
    """Write ``<path>.pgm`` and ``<path>.yaml`` (a ``.yaml`` or ``.pgm`` suffix on ``path`` is dropped).

    Args:
        path: Base name of the two files; missing parent folders are created.
        data: (height, width) int8 occupancy in ``OccupancyGrid`` layout (-1 unknown, 0..100).
        resolution: Cell size [m].
        origin: Map-frame (x, y) [m] of the corner of cell (0, 0).

    Returns:
        The YAML file's path.

    Raises:
        OSError: the files cannot be written.
    """
    base = Path(path)
    if base.suffix in (".yaml", ".pgm"):
        base = base.with_suffix("")
    base.parent.mkdir(parents=True, exist_ok=True)
    pixels = np.full(data.shape, 205, np.uint8)
    pixels[(data >= 0) & (data <= _FREE_INT)] = 254
    pixels[(data >= _OCC_INT) & (data <= 100)] = 0
    height, width = data.shape
    pgm = base.with_suffix(".pgm")
    pgm.write_bytes(f"P5\n# CREATOR: sigcore-slam {resolution:.3f} m/pix\n{width} {height}\n255\n".encode()
                    + np.ascontiguousarray(pixels[::-1]).tobytes())
    yaml = base.with_suffix(".yaml")
    yaml.write_text(f"image: {pgm.name}\nmode: trinary\nresolution: {resolution!r}\n"
                    f"origin: [{float(origin[0])!r}, {float(origin[1])!r}, 0.0]\nnegate: 0\n"
                    f"occupied_thresh: {OCCUPIED_THRESH}\nfree_thresh: {FREE_THRESH}\n")
    return yaml


def load_map(yaml: str | Path) -> MapFile:
    """Read a map_server YAML file and its PGM image (binary P5, 8 bit, trinary or scale mode read as trinary).

    Raises:
        ValueError: the YAML lacks a key or the image is not a binary 8-bit PGM.
        OSError: a file cannot be read.
    """
    yaml = Path(yaml)
    meta: dict[str, str] = {}
    for line in yaml.read_text().splitlines():
        key, sep, value = line.partition("#")[0].partition(":")
        if sep:
            meta[key.strip()] = value.strip()
    missing = [k for k in ("image", "resolution", "origin", "occupied_thresh", "free_thresh") if k not in meta]
    if missing:
        raise ValueError(f"{yaml}: missing {', '.join(missing)}; a map_server YAML has image, resolution, origin, "
                         "negate, occupied_thresh, free_thresh")
    origin = [float(v) for v in meta["origin"].strip("[]").split(",")]
    pixels = _read_pgm(yaml.parent / meta["image"].strip("'\""))
    occ = (255.0 - pixels.astype(np.float64)) / 255.0
    if meta.get("negate", "0").strip() in ("1", "true", "True"):
        occ = 1.0 - occ
    data = np.full(pixels.shape, -1, np.int8)
    data[occ > float(meta["occupied_thresh"])] = 100
    data[occ < float(meta["free_thresh"])] = 0
    return MapFile(np.ascontiguousarray(data[::-1]), float(meta["resolution"]),
                   (origin[0], origin[1], origin[2] if len(origin) > 2 else 0.0), yaml)


def _read_pgm(path: Path) -> npt.NDArray[np.uint8]:
    raw = path.read_bytes()
    fields: list[bytes] = []
    pos = 0
    while len(fields) < 4:
        while raw[pos:pos + 1].isspace():
            pos += 1
        if raw[pos:pos + 1] == b"#":
            pos = raw.index(b"\n", pos) + 1
            continue
        end = pos
        while end < len(raw) and not raw[end:end + 1].isspace():
            end += 1
        fields.append(raw[pos:end])
        pos = end
    if fields[0] != b"P5" or int(fields[3]) != 255:
        raise ValueError(f"{path}: not a binary 8-bit PGM (magic {fields[0]!r}, maxval {fields[3]!r}); "
                         "expected P5 with maxval 255")
    width, height = int(fields[1]), int(fields[2])
    body = raw[pos + 1:pos + 1 + width * height]
    if len(body) != width * height:
        raise ValueError(f"{path}: {len(body)} pixel bytes, expected {width} x {height}")
    return np.frombuffer(body, np.uint8).reshape(height, width)
