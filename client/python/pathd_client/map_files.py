"""Map files on the client's disk as CreateMap sources, as `pathctl maps
create --from FILE` reads them (client/map_source.cc): a Moving AI .map
travels as its text; a ROS map_server map as the YAML text plus the bytes of
the image it names. The server parses both, so the two clients can never
disagree about thresholds, origin or the PGM format; here only the YAML's
`image` entry is read (with PyYAML, Debian's python3-yaml)."""

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
