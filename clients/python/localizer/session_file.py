"""The session file: an array file (``array.json``) with its optional ``"session"`` object of
tracking settings, read in pure Python with the rules localizer-cli reads it by
(clients/io/array_json.h, clients/io/session_file.h), so that one file opens the same session
in ``localizer-cli track``, in ``localizer.engine.Session`` and on a server through
``TrackSession``::

    import localizer, localizer.engine as le
    sf = localizer.read_session_file("array.json")
    session = le.Session(sf.sensors_m, fs, **sf.engine_options(fs))      # in-process
    config = sf.to_session_config(fs, label="array-1")                    # pb.SessionConfig
    remote = localizer.TrackSession.open(channel, config)

The ``"session"`` keys are ``localizer.engine.Session``'s option names (``SESSION_KEYS``;
``frame_samples``, ``filter``, ``particles``, ``tdoa_sigma_s``, ...); localizer-cli reads each
as the default of one flag. What the array file's top level says (sound speed, reference
sensor, band hint, bounds, localization, max_sources, source_side, source_plane) stays there.

Every error is a ValueError naming the file and the field: an unknown key (at the top level or
in "session"), a key in the wrong place, a value of the wrong JSON type, an unknown name, and
the engine's ranges for the session settings, checked over the engine's defaults for what the
file leaves out (hop_samples <= frame_samples, 4096 when unset; a motion_model other than cv
needs filter ekf or ukf). The array's geometry (coplanar sensors, ...) is checked when a
session is opened, as is the band against the recording's Nyquist frequency.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from ._array_json import TOP_LEVEL, is_int, is_number, parse_array_fields
from ._stubs import pb
from .messages import bounds as _bounds, vector3

__all__ = ["SESSION_KEYS", "CHOICES", "SessionFile", "read_session_file", "parse_session_file"]

# The names each choice takes (the engine's tables: engine/filters/filter_kind.cc, ...).
CHOICES: dict[str, tuple[str, ...]] = {
    "weighting": ("phat", "phat-beta", "scot", "cc", "phat-coherence", "phat-share"),
    "filter": ("pf", "ekf", "ukf", "mmpf", "imm"),
    "motion_model": ("cv", "ca", "ct", "singer"),
    "imm_variant": ("ekf", "ukf"),
    "robust": ("none", "huber", "student-t"),
    "likelihood": ("peak", "gcc", "mixture"),
    "backend": ("auto", "cpu", "gpu"),
}
_INTS = ("frame_samples", "hop_samples", "particles")
_NUMBERS = ("phat_beta", "band_low_hz", "band_high_hz", "despike_k", "outlier_probability", "tdoa_sigma_s",
            "accel_noise_mps2", "manoeuvre_share", "manoeuvre_scale", "accel_level_floor", "accel_level_ceiling",
            "accel_level_switch_hz", "turn_rate_max_radps", "speed_change_max_mps2", "search_radius_m",
            "presence_false_alarm", "source_timeout_s")
_BOOLS = ("direction_diffuse_weighting", "direction_signal_weighting")
# Every "session" key, in clients/io/session_file.h's order.
SESSION_KEYS: tuple[str, ...] = (
    "frame_samples", "hop_samples", "weighting", "phat_beta", "band_low_hz", "band_high_hz", "despike_k",
    "filter", "motion_model", "imm_modes", "imm_variant", "robust", "particles", "likelihood",
    "outlier_probability", "tdoa_sigma_s", "accel_noise_mps2", "manoeuvre_share", "manoeuvre_scale",
    "accel_level_floor", "accel_level_ceiling", "accel_level_switch_hz", "turn_rate_max_radps",
    "speed_change_max_mps2", "seed", "search_radius_m",
    "presence_false_alarm", "source_timeout_s", "backend", "direction_present_hold_s", "direction_diffuse_weighting",
    "direction_signal_weighting")
# Keys that belong at the top level (the top-level fields, and localizer.engine's names of the
# source plane), refused in "session" saying so.
_MISPLACED = tuple(k for k in TOP_LEVEL if k != "session") + ("source_plane_point_m", "source_plane_normal")
_ENGINE_ONLY = ("max_block_samples", "init_speed_sigma_mps", "init_region_min_m", "init_region_max_m",
                "divergence_window")
# Engine defaults the range checks fall back on (engine::AudioSessionConfig).
_DEFAULTS = {"frame_samples": 4096, "filter": "pf", "accel_level_floor": 0.003, "accel_level_ceiling": 3.0}
_INT_MAX = 2**31 - 1


def _check_session(s: Any, where: str) -> dict[str, Any]:
    """The "session" object checked as clients/io/session_file.cc checks it."""
    if not isinstance(s, dict):
        raise ValueError(f"{where}: session is {json.dumps(s)}, not an object of settings")
    for key, v in s.items():
        name = f"{where}: session.{key}"
        if key in _MISPLACED:
            raise ValueError(f"{name}: give it at the top level of the array file, beside sensors_m, not in "
                             '"session"')
        if key in _ENGINE_ONLY:
            raise ValueError(f"{name}: not a session-file key: localizer-cli has no flag for it (pass it to "
                             "localizer.engine.Session directly)")
        if key not in SESSION_KEYS:
            raise ValueError(f'{where}: session: unknown key "{key}" (known: {", ".join(SESSION_KEYS)})')
        if key in _INTS and not (is_int(v) and -_INT_MAX - 1 <= v <= _INT_MAX):
            raise ValueError(f"{name} is {json.dumps(v)}, not an integer (or out of range)")
        if key == "seed" and not (is_int(v) and 0 <= v < 2**64):
            raise ValueError(f"{name} is {json.dumps(v)}, not an integer >= 0")
        if key in _BOOLS and not isinstance(v, bool):
            raise ValueError(f"{name} is {json.dumps(v)}, not true or false")
        if key in _NUMBERS and not is_number(v):
            raise ValueError(f"{name} is {json.dumps(v)}, not a finite number")
        if key in CHOICES or key == "imm_modes":
            if not isinstance(v, str):
                raise ValueError(f"{name} is {json.dumps(v)}, not a name (a string)")
            names = v.split(",") if key == "imm_modes" else [v]
            allowed = CHOICES["motion_model" if key == "imm_modes" else key]
            for n in names:
                if n not in allowed:
                    raise ValueError(f"{name} '{v}' is not one of: {', '.join(allowed)}")
            if len(set(names)) != len(names):
                raise ValueError(f"{name} '{v}' names a mode twice")
    _check_ranges({**_DEFAULTS, **s}, where)
    return dict(s)


def _check_ranges(s: Mapping[str, Any], where: str) -> None:
    """The engine's ranges (AudioSessionConfig::Validate, GccOptions::Validate,
    ParticleFilterOptions::Validate) on the settings over the defaults."""
    def refuse(key: str, rule: str) -> None:
        raise ValueError(f"{where}: session: {key} must be {rule}, got {s[key]}")

    def check(key: str, ok: bool, rule: str) -> None:
        if key in s and not ok:
            refuse(key, rule)

    g = s.get
    check("frame_samples", 64 <= g("frame_samples", 64) <= 2**20, "in [64, 1048576]")
    check("hop_samples", 1 <= g("hop_samples", 1) <= s["frame_samples"], f"in [1, frame_samples={s['frame_samples']}]")
    check("phat_beta", 0.0 <= g("phat_beta", 0.0) <= 1.0, "in [0, 1]")
    check("band_low_hz", g("band_low_hz", 0.0) >= 0.0, ">= 0")
    check("band_high_hz", g("band_high_hz", 0.0) >= 0.0, ">= 0")
    check("band_high_hz", g("band_high_hz", 0.0) == 0.0 or g("band_high_hz") > g("band_low_hz", 0.0),
          "0 (up to Nyquist) or above band_low_hz")
    check("despike_k", g("despike_k", 0.0) == 0.0 or 1.0 <= g("despike_k") <= 1e6, "0 (off) or in [1, 1e6]")
    check("motion_model", g("motion_model", "cv") == "cv" or s["filter"] in ("ekf", "ukf"),
          "cv unless filter is ekf or ukf")
    check("particles", 16 <= g("particles", 16) <= 2**22, "in [16, 4194304]")
    check("outlier_probability", 0.0 <= g("outlier_probability", 0.0) < 1.0, "in [0, 1)")
    check("tdoa_sigma_s", g("tdoa_sigma_s", 0.0) >= 0.0, ">= 0 (0: adaptive)")
    check("accel_noise_mps2", g("accel_noise_mps2", 0.0) >= 0.0, ">= 0")
    check("manoeuvre_share", 0.0 <= g("manoeuvre_share", 0.0) < 1.0, "in [0, 1)")
    check("manoeuvre_scale", g("manoeuvre_scale", 1.0) >= 1.0, ">= 1")
    floor, ceiling = s["accel_level_floor"], s["accel_level_ceiling"]
    if not 1e-6 <= floor <= ceiling <= 100.0:
        refuse("accel_level_floor" if "accel_level_floor" in s else "accel_level_ceiling",
               f"1e-6 <= floor <= ceiling <= 100 (floor {floor}, ceiling {ceiling})")
    check("accel_level_switch_hz", 0.0 <= g("accel_level_switch_hz", 0.0) <= 1000.0, "in [0, 1000]")
    check("turn_rate_max_radps", 0.0 <= g("turn_rate_max_radps", 0.0) <= 5.0, "in [0, 5] rad/s")
    check("speed_change_max_mps2", 0.0 <= g("speed_change_max_mps2", 0.0) <= 20.0, "in [0, 20] m/s^2")
    check("search_radius_m", 0.0 <= g("search_radius_m", 0.0) <= 1e7, "in [0, 1e7]")
    check("presence_false_alarm", 0.0 < g("presence_false_alarm", 1e-3) <= 0.1, "in (0, 0.1]")
    check("source_timeout_s", 0.0 < g("source_timeout_s", 1.0) <= 1e6, "in (0, 1e6]")
    check("direction_present_hold_s", 0.0 <= g("direction_present_hold_s", 0.0) <= 1.0, "in [0, 1] s")


@dataclass(frozen=True, eq=False)  # eq: sensors_m is an array
class SessionFile:
    """An array file and its session settings, checked (see the module's docstring)."""
    path: str
    sensors_m: np.ndarray  # (N, 3) float64, metres
    sound_speed_mps: float
    sample_rate_hz: float | None = None  # the file's; a recording's own rate wins
    reference_sensor: int = 0
    band_hz: tuple[float, float] | None = None  # the source band hint
    bounds_min_m: tuple[float, float, float] = (-math.inf,) * 3  # open sides infinite
    bounds_max_m: tuple[float, float, float] = (math.inf,) * 3
    localization: str = "auto"
    max_sources: int | None = None
    source_side: tuple[float, float, float] | None = None
    source_plane: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None  # point_m, normal
    geodetic_origin: dict[str, float] | None = None
    session: dict[str, Any] = field(default_factory=dict)  # the "session" object as written

    def _band(self, sample_rate_hz: float | None) -> tuple[float, float] | None:
        """The GCC band as localizer-cli sets it (io::TrackConfigFor): the session's, else the
        band_hz hint with its high edge capped at Nyquist; None: the whole spectrum."""
        low, high = self.session.get("band_low_hz", 0.0), self.session.get("band_high_hz", 0.0)
        if low == 0.0 and high == 0.0 and self.band_hz is not None:
            low, high = self.band_hz
            if sample_rate_hz:
                high = min(high, 0.5 * sample_rate_hz)
        return None if low == 0.0 and high == 0.0 else (float(low), float(high))

    @property
    def options(self) -> dict[str, Any]:
        """``engine_options`` at the file's own sample rate."""
        return self.engine_options(self.sample_rate_hz)

    def engine_options(self, sample_rate_hz: float | None = None) -> dict[str, Any]:
        """The keyword options of ``localizer.engine.Session(sensors_m, sample_rate_hz, **options)``
        that open the session ``localizer-cli track`` opens with this file and no flags, for a
        recording at ``sample_rate_hz`` (it caps the band hint at Nyquist; None: not capped)."""
        options: dict[str, Any] = {"sound_speed_mps": self.sound_speed_mps, "reference_sensor": self.reference_sensor,
                                   "localization": self.localization}
        options.update(self.session)
        band = self._band(sample_rate_hz)
        if band is not None:
            options["band_low_hz"], options["band_high_hz"] = band
        if any(math.isfinite(x) for x in self.bounds_min_m + self.bounds_max_m):
            options["bounds_min_m"], options["bounds_max_m"] = self.bounds_min_m, self.bounds_max_m
        if self.max_sources is not None:
            options["max_sources"] = self.max_sources
        if self.source_side is not None:
            options["source_side"] = self.source_side
        if self.source_plane is not None:
            options["source_plane_point_m"], options["source_plane_normal"] = self.source_plane
        return options

    def to_session_config(self, sample_rate_hz: float | None = None, *, label: str = "") -> pb.SessionConfig:
        """The ``pb.SessionConfig`` of this file for a recording at ``sample_rate_hz`` (default:
        the file's): what the file states is set, the rest left at zero / unset, which the
        server reads as the engine default. Unlike ``localizer-cli track --server`` (which
        sends every field resolved), a session that lists sources gets the server's 4096-sample
        frames unless the file states frame_samples. ValueError when there is no rate, or for
        a setting the wire cannot carry (0 where the wire reads 0 as "the default")."""
        rate = sample_rate_hz if sample_rate_hz is not None else self.sample_rate_hz
        if rate is None:
            raise ValueError(f"{self.path}: no sample_rate_hz in the file; pass the recording's")
        s = self.session
        for key, default in (("accel_noise_mps2", "1"), ("phat_beta", "0.8"), ("outlier_probability", "0.05")):
            if s.get(key) == 0:
                raise ValueError(f"{self.path}: session.{key} = 0 cannot be sent: pb.SessionConfig reads 0 as the "
                                 f"default ({default})")
        config = pb.SessionConfig(
            array=pb.ArrayGeometry(sensors_m=[vector3(p) for p in self.sensors_m],
                                   sound_speed_mps=self.sound_speed_mps, reference_sensor=self.reference_sensor),
            sample_rate_hz=float(rate), label=label, localization=self.localization)
        band = self._band(rate)
        if band is not None:
            config.band_low_hz, config.band_high_hz = band
        for key in ("frame_samples", "hop_samples", "phat_beta", "despike_k", "seed", "search_radius_m",
                    "presence_false_alarm", "source_timeout_s", "backend", "direction_present_hold_s",
                    "direction_diffuse_weighting", "direction_signal_weighting"):
            if key in s:
                setattr(config, key, s[key])
        if "weighting" in s:
            config.weighting = pb.Weighting.Value("WEIGHTING_" + s["weighting"].upper().replace("-", "_"))
        f = config.filter
        if "filter" in s:
            f.type = pb.FilterType.Value("FILTER_TYPE_" + s["filter"].upper())
        if "likelihood" in s:
            f.likelihood = pb.Likelihood.Value("LIKELIHOOD_" + s["likelihood"].upper())
        for key in ("motion_model", "imm_modes", "imm_variant", "robust", "particles", "outlier_probability",
                    "tdoa_sigma_s", "accel_noise_mps2", "manoeuvre_share", "manoeuvre_scale", "accel_level_floor",
                    "accel_level_ceiling"):
            if key in s:
                setattr(f, key, s[key])
        if "accel_level_switch_hz" in s:  # the wire's 0 is the default; a rate of 0 goes as -1
            f.accel_level_switch_hz = s["accel_level_switch_hz"] if s["accel_level_switch_hz"] > 0 else -1.0
        if "turn_rate_max_radps" in s:  # likewise: no turn rates go as -1
            f.turn_rate_max_radps = s["turn_rate_max_radps"] if s["turn_rate_max_radps"] > 0 else -1.0
        if "speed_change_max_mps2" in s:  # likewise: no speed changes go as -1
            f.speed_change_max_mps2 = s["speed_change_max_mps2"] if s["speed_change_max_mps2"] > 0 else -1.0
        if any(math.isfinite(x) for x in self.bounds_min_m + self.bounds_max_m):
            config.bounds.CopyFrom(_bounds(self.bounds_min_m, self.bounds_max_m))
        if self.max_sources is not None:
            config.max_sources = self.max_sources
        if self.source_side is not None:
            config.source_side.CopyFrom(vector3(self.source_side))
        if self.source_plane is not None:
            config.source_plane.point_m.CopyFrom(vector3(self.source_plane[0]))
            config.source_plane.normal.CopyFrom(vector3(self.source_plane[1]))
        return config


def read_session_file(path: str | os.PathLike) -> SessionFile:
    """The array file at ``path`` with its session settings; FileNotFoundError, or ValueError
    naming the file and the field."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    return parse_session_file(text, os.fspath(path))


def parse_session_file(text: str, source: str = "array.json") -> SessionFile:
    """``read_session_file`` on text; ``source`` names it in messages."""
    try:
        root = json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"{source}: not valid JSON: {e}") from None
    if not isinstance(root, dict):
        raise ValueError(f"{source}: top level must be a JSON object")
    fields = parse_array_fields(root, source)
    if "session" in root:
        fields["session"] = _check_session(root["session"], source)
    return SessionFile(path=source, **fields)


