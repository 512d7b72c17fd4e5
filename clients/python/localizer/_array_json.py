"""array.json's top level read in pure Python, checked as clients/io/array_json.cc checks it
(the geometry aside: the engine checks that when a session is opened). For
localizer.session_file, which adds the "session" object."""
from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

# The top-level fields (clients/io/array_json.cc, kKnownFields).
TOP_LEVEL = ("sound_speed_mps", "sample_rate_hz", "sensors_m", "reference_sensor", "band_hz", "bounds_min_m",
             "bounds_max_m", "surface_z_m", "bottom_z_m", "localization", "source_side", "max_sources",
             "source_plane", "geodetic_origin", "session")


def is_int(v: Any) -> bool:
    """A JSON integer (json.loads gives int; a bool is not one)."""
    return isinstance(v, int) and not isinstance(v, bool)  # JSON true is not 1


def is_number(v: Any) -> bool:
    """A finite JSON number."""
    return (is_int(v) or isinstance(v, float)) and math.isfinite(v)


def _vector(v: Any, name: str) -> tuple[float, float, float]:
    if not (isinstance(v, list) and len(v) == 3 and all(is_number(x) for x in v)):
        raise ValueError(f"{name} must be [x, y, z] of finite numbers, got {json.dumps(v)}")
    return (float(v[0]), float(v[1]), float(v[2]))


def _bounds_side(v: Any, name: str, is_min: bool) -> list[float]:
    open_text, open_value = ("-inf", -math.inf) if is_min else ("inf", math.inf)
    if not (isinstance(v, list) and len(v) == 3):
        raise ValueError(f"{name} is {json.dumps(v)}, not [x, y, z] (a number or null per axis; null = open)")
    side = []
    for axis, x in enumerate(v):
        if x is None or x == open_text:
            side.append(open_value)
        elif is_number(x):
            side.append(float(x))
        else:
            raise ValueError(f'{name}[{axis}] is {json.dumps(x)}; must be a finite number, or null or "{open_text}"')
    return side


def parse_array_fields(root: dict, source: str) -> dict[str, Any]:
    """The top level's fields of an array file as SessionFile's (its "session" aside), checked;
    ValueError naming ``source`` and the field."""
    for key in root:
        if key not in TOP_LEVEL:
            raise ValueError(f'{source}: unknown field "{key}" (known: {", ".join(TOP_LEVEL)})')
    for key in ("sound_speed_mps", "sensors_m"):
        if key not in root:
            raise ValueError(f"{source}: missing required field {key}")
    c = root["sound_speed_mps"]
    if not (is_number(c) and c > 0):
        raise ValueError(f"{source}: sound_speed_mps is {json.dumps(c)}, must be a number > 0")
    rows = root["sensors_m"]
    if not isinstance(rows, list):
        raise ValueError(f"{source}: sensors_m must be an array of [x, y, z] rows")
    sensors = np.array([_vector(r, f"{source}: sensors_m[{k}]") for k, r in enumerate(rows)], float).reshape(-1, 3)
    fields: dict[str, Any] = {"sensors_m": sensors, "sound_speed_mps": float(c)}
    if "sample_rate_hz" in root:
        rate = root["sample_rate_hz"]
        if not (is_number(rate) and rate > 0):
            raise ValueError(f"{source}: sample_rate_hz is {json.dumps(rate)}, must be a number > 0")
        fields["sample_rate_hz"] = float(rate)
    if "reference_sensor" in root:
        ref = root["reference_sensor"]
        if not (is_int(ref) and 0 <= ref < len(sensors)):
            raise ValueError(f"{source}: reference_sensor is {json.dumps(ref)}, not one of the sensors")
        fields["reference_sensor"] = ref
    if "band_hz" in root:
        band = root["band_hz"]
        if not (isinstance(band, list) and len(band) == 2 and all(is_number(x) for x in band)
                and 0 <= band[0] < band[1]):
            raise ValueError(f"{source}: band_hz must be [low, high] with 0 <= low < high, got {json.dumps(band)}")
        fields["band_hz"] = (float(band[0]), float(band[1]))
    fields.update(_parse_bounds(root, source))
    fields.update(_parse_direction_fields(root, source))
    if "geodetic_origin" in root:
        fields["geodetic_origin"] = _parse_geodetic_origin(root["geodetic_origin"], source)
    return fields


def _parse_bounds(root: dict, source: str) -> dict[str, Any]:
    lo, hi = [-math.inf] * 3, [math.inf] * 3
    if "bounds_min_m" in root:
        lo = _bounds_side(root["bounds_min_m"], f"{source}: bounds_min_m", True)
    if "bounds_max_m" in root:
        hi = _bounds_side(root["bounds_max_m"], f"{source}: bounds_max_m", False)
    # A water column with z up: the surface is the upper z bound, the bottom the lower.
    for key, side, other in (("surface_z_m", hi, "bounds_max_m[2]"), ("bottom_z_m", lo, "bounds_min_m[2]")):
        if key in root:
            if not is_number(root[key]):
                raise ValueError(f"{source}: {key} is {json.dumps(root[key])}, not a number")
            if math.isfinite(side[2]):
                raise ValueError(f"{source}: {key} and {other} both give the same z bound; keep one")
            side[2] = float(root[key])
    for axis, name in enumerate("xyz"):
        if not lo[axis] < hi[axis]:
            raise ValueError(f"{source}: the {name} bounds are empty: min {lo[axis]} must be below max {hi[axis]}")
    return {"bounds_min_m": tuple(lo), "bounds_max_m": tuple(hi)}


def _parse_direction_fields(root: dict, source: str) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if "localization" in root:
        if root["localization"] not in ("auto", "position", "direction"):
            raise ValueError(f'{source}: localization must be "auto", "position" or "direction", got '
                             f'{json.dumps(root["localization"])}')
        out["localization"] = root["localization"]
    if "source_side" in root:
        side = root["source_side"]
        if not (isinstance(side, dict) and list(side) == ["normal"]):
            raise ValueError(f'{source}: source_side must be {{"normal": [x, y, z]}}')
        out["source_side"] = _vector(side["normal"], f"{source}: source_side.normal")
        if not any(out["source_side"]):
            raise ValueError(f"{source}: source_side.normal must not be zero")
    if "source_plane" in root:
        plane = root["source_plane"]
        if not (isinstance(plane, dict) and sorted(plane) == ["normal", "point_m"]):
            raise ValueError(f'{source}: source_plane must be {{"point_m": [x, y, z], "normal": [nx, ny, nz]}}')
        normal = _vector(plane["normal"], f"{source}: source_plane.normal")
        if not any(normal):
            raise ValueError(f"{source}: source_plane.normal must not be zero")
        out["source_plane"] = (_vector(plane["point_m"], f"{source}: source_plane.point_m"), normal)
    if "max_sources" in root:
        k = root["max_sources"]
        if not (is_int(k) and 1 <= k <= 16):
            raise ValueError(f"{source}: max_sources must be an integer in [1, 16], got {json.dumps(k)}")
        out["max_sources"] = k
    return out


def _parse_geodetic_origin(g: Any, source: str) -> dict[str, float]:
    known = ("latitude_deg", "longitude_deg", "altitude_m", "heading_deg")
    if not (isinstance(g, dict) and "latitude_deg" in g and "longitude_deg" in g):
        raise ValueError(f'{source}: geodetic_origin must be {{"latitude_deg": ..., "longitude_deg": ..., '
                         '"altitude_m": ... (optional), "heading_deg": ... (optional)}')
    for key, v in g.items():
        if key not in known:
            raise ValueError(f'{source}: geodetic_origin: unknown field "{key}" (known: {", ".join(known)})')
        if not is_number(v):
            raise ValueError(f"{source}: geodetic_origin.{key} is {json.dumps(v)}, not a number")
    if not (abs(g["latitude_deg"]) <= 90 and abs(g["longitude_deg"]) <= 180):
        raise ValueError(f"{source}: geodetic_origin: latitude_deg must be in [-90, 90] and longitude_deg in "
                         "[-180, 180]")
    return {key: float(v) for key, v in g.items()}
