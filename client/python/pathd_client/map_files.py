"""Map files on the client's disk as CreateMap sources, as `pathctl maps
create --from FILE` reads them (client/map_source.cc): a Moving AI .map
travels as its text; a ROS map_server map as the YAML text plus the bytes of
the image it names. The server parses both, so the two clients can never
disagree about thresholds, origin or the PGM format; here only the YAML's
`image` entry is read (with PyYAML, Debian's python3-yaml). A file too large
for one message is parsed here instead (cells_from_file, by the rules of
core/map_io) and streamed through UploadMap, as pathctl does."""

from __future__ import annotations

import os
import pathlib

from pathd.v1 import map_service_pb2

MOVINGAI_SUFFIXES = (".map",)
ROS_SUFFIXES = (".yaml", ".yml")


def _ros_image_name(yaml_text: str, path: pathlib.Path) -> str:
    try:
        import yaml  # pylint: disable=import-outside-toplevel
    except ImportError:
        raise ImportError("reading a ROS map_server .yaml needs PyYAML "
                          "(Debian: python3-yaml)") from None
    try:
        document = yaml.safe_load(yaml_text)
    except yaml.YAMLError as error:
        raise ValueError(f"{path}: invalid YAML: {error}") from None
    if not isinstance(document, dict):
        raise ValueError(f"{path}: expected a YAML mapping with image, resolution and origin")
    image = document.get("image")
    if image is None or not isinstance(image, str) or not image:
        raise ValueError(f"{path}: the YAML names no image")
    return image


def set_source_from_file(request: map_service_pb2.CreateMapRequest,
                         path: str | os.PathLike) -> None:
    """Sets request's source from the file at `path`: .map (Moving AI) or
    .yaml / .yml (ROS map_server; its image, relative to the YAML's folder
    unless absolute, as map_server resolves it). ValueError naming the file
    for an unknown extension or a YAML without an image; OSError (e.g.
    FileNotFoundError) when a file cannot be read."""
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix in MOVINGAI_SUFFIXES:
        request.movingai_text = path.read_text(encoding="utf-8", errors="replace")
    elif suffix in ROS_SUFFIXES:
        yaml_text = path.read_text(encoding="utf-8")
        image = pathlib.Path(_ros_image_name(yaml_text, path))
        if not image.is_absolute():
            image = path.parent / image
        request.ros_map.CopyFrom(map_service_pb2.RosMap(yaml=yaml_text,
                                                        image=image.read_bytes()))
    else:
        raise ValueError(f"{path}: unknown map file type; expected .map (Moving AI) "
                         "or .yaml/.yml (ROS map_server)")


# Moving AI's terrain classes for ground-based paths (core/map_io/movingai.cc):
# passable {. G S}, blocked {@ O T W}.
_MOVINGAI_COSTS = bytes(0 if chr(c) in ".GS" else 254 for c in range(256))
_MOVINGAI_CHARS = b".GS@OTW"


def parse_movingai(text: bytes, path) -> tuple[int, int, bytes]:
    """(width, height, cost bytes) of Moving AI .map text; ValueError naming
    `path` and the problem."""
    lines = text.replace(b"\r\n", b"\n").split(b"\n")
    try:
        if not lines[0].startswith(b"type") or lines[3].strip() != b"map":
            raise ValueError
        height = int(lines[1].split()[1]) if lines[1].split()[0] == b"height" else None
        width = int(lines[2].split()[1]) if lines[2].split()[0] == b"width" else None
    except (ValueError, IndexError):
        raise ValueError(f"{path}: not a Moving AI map header (type, height, width, map)") from None
    if not height or not width or height < 1 or width < 1:
        raise ValueError(f"{path}: height and width must be positive")
    rows = lines[4:4 + height]
    if len(rows) < height:
        raise ValueError(f"{path}: {len(rows)} map rows, the header says {height}")
    for y, row in enumerate(rows):
        if len(row) != width:
            raise ValueError(f"{path}:{y + 5}: row of {len(row)} characters, expected {width}")
    body = b"".join(rows)
    bad = body.translate(None, _MOVINGAI_CHARS)
    if bad:
        raise ValueError(f"{path}: character {bad[:1]!r}; expected one of . G S @ O T W")
    return width, height, body.translate(_MOVINGAI_COSTS)


def _ros_cost_table(negate: bool, occupied: float, free: float, mode: str,
                    maxval: int) -> bytes:
    # As core/map_io/ros_map.cc's MakeCostTable.
    table = bytearray(maxval + 1)
    for v in range(maxval + 1):
        if mode == "raw":
            table[v] = min(v, 255)
            continue
        p = v / maxval if negate else (maxval - v) / maxval
        if p > occupied:
            table[v] = 254
        elif p < free:
            table[v] = 0
        elif mode == "trinary":
            table[v] = 255
        else:
            t = (p - free) / (occupied - free)
            table[v] = min(max(1 + int(t * 251 + 0.5), 1), 252)
    return bytes(table) + bytes(256 - len(table))


def _parse_ros(path: pathlib.Path):
    import yaml  # pylint: disable=import-outside-toplevel
    document = yaml.safe_load(path.read_text(encoding="utf-8"))
    if not isinstance(document, dict):
        raise ValueError(f"{path}: expected a YAML mapping")
    try:
        resolution = float(document["resolution"])
        origin = tuple(float(v) for v in document["origin"])
        negate = bool(int(document.get("negate", 0)))
        occupied = float(document.get("occupied_thresh", 0.65))
        free = float(document.get("free_thresh", 0.196))
        mode = str(document.get("mode", "trinary"))
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"{path}: bad or missing field: {error}") from None
    if not (resolution > 0 and len(origin) == 3 and 0 <= free < occupied <= 1
            and mode in ("trinary", "scale", "raw")):
        raise ValueError(f"{path}: resolution, origin, thresholds or mode out of range")
    image = pathlib.Path(_ros_image_name(path.read_text(encoding="utf-8"), path))
    if not image.is_absolute():
        image = path.parent / image
    pgm = image.read_bytes()
    fields = pgm.split(maxsplit=4)
    if len(fields) < 5 or fields[0] != b"P5":
        raise ValueError(f"{image}: streaming reads binary (P5) PGMs; this is not one")
    width, height, maxval = int(fields[1]), int(fields[2]), int(fields[3])
    if maxval > 255:
        raise ValueError(f"{image}: streaming reads 8-bit PGMs; maxval is {maxval}")
    raster = pgm[len(pgm) - len(fields[4]):][:width * height]
    if len(raster) < width * height:
        raise ValueError(f"{image}: truncated pixel data")
    # Image row r is grid row height - 1 - r (the OccupancyGrid convention).
    flipped = b"".join(raster[(height - 1 - r) * width:(height - r) * width]
                       for r in range(height))
    table = _ros_cost_table(negate, occupied, free, mode, maxval)
    return width, height, flipped.translate(table), resolution, origin


def cells_from_file(path: str | os.PathLike):
    """(width, height, cost bytes, resolution or None, origin or None) of a
    map file, parsed here by the server's rules (core/map_io): for files
    too large for one CreateMap message, which the client streams through
    UploadMap. Moving AI .map (resolution and origin None: the caller's), or
    a ROS .yaml with an 8-bit binary (P5) PGM. ValueError naming the file."""
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix in MOVINGAI_SUFFIXES:
        width, height, cells = parse_movingai(path.read_bytes(), path)
        return width, height, cells, None, None
    if suffix in ROS_SUFFIXES:
        return _parse_ros(path)
    raise ValueError(f"{path}: unknown map file type; expected .map (Moving AI) "
                     "or .yaml/.yml (ROS map_server)")
