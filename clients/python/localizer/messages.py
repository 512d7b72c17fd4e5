"""Building the service's request messages (session configs, bounds, IMU batches, scans)
from plain Python and numpy values, and a presence summary over a run's estimates. Blocks
are built in ``blocks``, estimates read in ``estimates``."""
from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np
import numpy.typing as npt

from ._stubs import pb

__all__ = ["vector3", "session_config", "bounds", "presence_summary", "platform_config",
           "detection_config", "imu_batch", "scan"]

Triple = Sequence[float]


def vector3(xyz: Triple) -> pb.Vector3:
    """A ``pb.Vector3`` from any 3-sequence (metres or m/s)."""
    x, y, z = (float(v) for v in xyz)
    return pb.Vector3(x=x, y=y, z=z)


def session_config(sensors_m: npt.ArrayLike, sample_rate_hz: float, *,
                   sound_speed_mps: float = 1500.0, reference_sensor: int = 0,
                   frame_samples: int = 0, hop_samples: int = 0, particles: int = 0,
                   band_hz: tuple[float, float] | None = None, seed: int | None = None,
                   backend: str = "", label: str = "",
                   init_region: tuple[Triple, Triple] | None = None,
                   platform: pb.PlatformConfig | None = None, bounds: pb.Bounds | None = None,
                   search_radius_m: float = 0.0, presence_false_alarm: float = 0.0,
                   source_timeout_s: float = 0.0, localization: str = "",
                   max_sources: int | None = None, source_side: Triple | None = None,
                   source_plane: tuple[Triple, Triple] | None = None) -> pb.SessionConfig:
    """A ``pb.SessionConfig``.

    sensors_m: (C, 3) sensor positions, metres (C >= 2; a position needs 4 off a common plane).
    localization: "position", "direction" or "auto" / "" (position for a volumetric array,
    directions for a planar or linear one: SessionOpened.localization says which; each
    estimate's ``sources`` then lists the sources followed, ``localizer.Source``). max_sources:
    sources per frame, 1..16 (None: 4 for directions, one tracked source for a volumetric
    array's positions; 2 or more there: that many sources, each with its position). source_side: (x, y, z), a planar
    array's side that holds the sources (None: not stated; mirror images); with a linear array,
    the side within source_plane. source_plane: ((x, y, z) point, (nx, ny, nz) normal), the
    plane holding a linear array and its sources: positions per source (localization
    "position", or "auto" with it). band_hz: (low, high) of
    the GCC band or None for the whole spectrum. init_region: ((xmin, ymin, zmin), (xmax, ymax,
    zmax)) or None. Zero / empty values mean "the server's default" (frame 4096, hop frame/2,
    4096 particles, seed 1, the server's --backend); SessionOpened.effective_config tells.
    platform: a ``platform_config()`` for a moving array (sensors_m then in the body frame;
    send ``imu_batch``es with ``TrackSession.send_imu`` before the blocks they cover).
    bounds: a ``bounds()`` box that can hold the source (None: unbounded). search_radius_m:
    the acquisition search radius about the array centre, m (0: 10 apertures).
    presence_false_alarm: per-frame false-alarm probability of the source-presence test, in
    (0, 0.1] (0: 0.001). source_timeout_s: how long a track coasts with no source heard
    before it is dropped, s (0: 2 s). Each estimate then says ``source_present`` (with
    ``presence_statistic`` and ``presence_threshold``), ``ambiguous`` and ``modes``.
    """
    config = pb.SessionConfig(
        array=pb.ArrayGeometry(sensors_m=[vector3(p) for p in np.asarray(sensors_m, float)],
                               sound_speed_mps=sound_speed_mps,
                               reference_sensor=reference_sensor),
        sample_rate_hz=sample_rate_hz, frame_samples=frame_samples, hop_samples=hop_samples,
        filter=pb.FilterConfig(particles=particles), backend=backend, label=label)
    if band_hz is not None:
        config.band_low_hz, config.band_high_hz = (float(f) for f in band_hz)
    if seed is not None:
        config.seed = seed
    if init_region is not None:
        config.init_region.min_m.CopyFrom(vector3(init_region[0]))
        config.init_region.max_m.CopyFrom(vector3(init_region[1]))
    if platform is not None:
        config.platform.CopyFrom(platform)
    if bounds is not None:
        config.bounds.CopyFrom(bounds)
    config.search_radius_m = float(search_radius_m)
    config.presence_false_alarm = float(presence_false_alarm)
    config.source_timeout_s = float(source_timeout_s)
    config.localization = localization
    if max_sources is not None:
        config.max_sources = int(max_sources)
    if source_side is not None:
        config.source_side.CopyFrom(vector3(source_side))
    if source_plane is not None:
        config.source_plane.point_m.CopyFrom(vector3(source_plane[0]))
        config.source_plane.normal.CopyFrom(vector3(source_plane[1]))
    return config


def bounds(min_m: Sequence[float | None] | None = None, max_m: Sequence[float | None] | None = None,
           *, surface_z_m: float | None = None, bottom_z_m: float | None = None) -> pb.Bounds:
    """A ``pb.Bounds``: the box that can hold the source, metres, world frame.

    min_m, max_m: (x, y, z) corners or None; an axis that is None or infinite (-inf in min_m,
    +inf in max_m) is open (left unset on the wire). A water column with z up:
    ``bounds(surface_z_m=0.0, bottom_z_m=-8.0)`` (the surface is the upper z side, the
    bottom the lower; giving one together with that side of max_m / min_m is a ValueError).
    The server refuses a side that is not finite or an axis whose min is not below its max
    with INVALID_ARGUMENT naming the field (``bounds.min_z_m``, ...).
    """
    b = pb.Bounds()
    for corner, prefix in ((min_m, "min"), (max_m, "max")):
        if corner is None:
            continue
        for axis, value in zip("xyz", corner):
            if value is None:
                continue
            value = float(value)
            if np.isinf(value) and (value < 0) == (prefix == "min"):
                continue  # open side
            setattr(b, f"{prefix}_{axis}_m", value)
    for value, field in ((surface_z_m, "max_z_m"), (bottom_z_m, "min_z_m")):
        if value is None:
            continue
        if b.HasField(field):
            raise ValueError(f"bounds: {field} given twice (as a corner and as the "
                             f"{'surface' if field == 'max_z_m' else 'bottom'})")
        setattr(b, field, float(value))
    return b


def presence_summary(estimates: Iterable) -> dict:
    """Source presence over a run (``localizer.Estimate``s or raw ``pb.Estimate``s): a dict
    with ``frames``, ``tested`` (estimates whose presence test ran: threshold > 0),
    ``present``, ``ambiguous``, ``max_statistic`` and the ``threshold`` of that frame, and ``no_source`` (frames were tested and none held a
    source; the line ``localizer-cli`` prints then is ``no_source_line``); ``initialised``
    (positions) and ``far_field`` (of those, the ones whose frame could not bound the range:
    trust their direction from the array's centroid, not their range)."""
    out = {"frames": 0, "tested": 0, "present": 0, "ambiguous": 0, "max_statistic": 0.0,
           "threshold": 0.0, "initialised": 0, "far_field": 0}
    for e in estimates:
        out["frames"] += 1
        out["present"] += int(e.source_present)
        out["ambiguous"] += int(e.ambiguous)
        out["initialised"] += int(e.initialised)
        out["far_field"] += int(e.initialised and e.far_field)
        if e.presence_threshold > 0.0:
            if out["tested"] == 0 or e.presence_statistic > out["max_statistic"]:
                out["max_statistic"] = e.presence_statistic
                out["threshold"] = e.presence_threshold
            out["tested"] += 1
    out["no_source"] = out["tested"] > 0 and out["present"] == 0
    out["no_source_line"] = (
        f"no source found in {out['frames']} frames (presence statistic max "
        f"{out['max_statistic']:.3g}, threshold {out['threshold']:.3g})" if out["no_source"] else "")
    return out


def platform_config(*, attitude_filter: str = "", use_magnetometer: bool = False,
                    mag_declination_rad: float = 0.0,
                    origin_m: Triple = (0.0, 0.0, 0.0)) -> pb.PlatformConfig:
    """A ``pb.PlatformConfig``: the array rides a platform whose attitude comes from its IMU
    ("quaternion" filter by default, or "euler"); origin_m: the body origin in the world."""
    return pb.PlatformConfig(attitude_filter=attitude_filter, use_magnetometer=use_magnetometer,
                             mag_declination_rad=mag_declination_rad, origin_m=vector3(origin_m))


def detection_config(*, label: str = "", dimensions: int = 0, range_sigma_m: float = 0.0,
                     bearing_sigma_rad: float = 0.0, **detections) -> pb.SessionConfig:
    """A ``pb.SessionConfig`` for a detection (track-while-scan) session: the session takes
    ``scan()``s of plots and answers each with a ``pb.TrackList``. Keyword arguments are
    ``pb.DetectionConfig`` fields (confirm_hits, gate_probability, ...); 0 means the default."""
    d = pb.DetectionConfig(dimensions=dimensions, range_sigma_m=range_sigma_m,
                           bearing_sigma_rad=bearing_sigma_rad, **detections)
    return pb.SessionConfig(detections=d, label=label)


def imu_batch(sequence: int, t_s: npt.ArrayLike, gyro_rps: npt.ArrayLike,
              accel_mps2: npt.ArrayLike, mag_uT: npt.ArrayLike | None = None,
              origin_m: Triple | None = None) -> pb.ImuBatch:
    """A ``pb.ImuBatch`` from arrays: t_s (N,), gyro_rps and accel_mps2 (N, 3), mag_uT (N, 3)
    or None; times on the session clock (seconds from its first audio sample), increasing."""
    batch = pb.ImuBatch(sequence=sequence)
    t_s = np.asarray(t_s, float)
    gyro, accel = np.asarray(gyro_rps, float), np.asarray(accel_mps2, float)
    mag = None if mag_uT is None else np.asarray(mag_uT, float)
    for i in range(len(t_s)):
        sample = batch.samples.add(t_s=float(t_s[i]), gyro_rps=vector3(gyro[i]),
                                   accel_mps2=vector3(accel[i]))
        if mag is not None:
            sample.mag_uT.CopyFrom(vector3(mag[i]))
    if origin_m is not None:
        batch.origin_m.CopyFrom(vector3(origin_m))
    return batch


def scan(sequence: int, time_s: float, ranges_m: Sequence[float], bearings_rad: Sequence[float],
         *, elevations_rad: Sequence[float] | None = None, snr_db: Sequence[float] | None = None,
         sensor_position_m: Triple = (0.0, 0.0, 0.0)) -> pb.Scan:
    """A ``pb.Scan``: one sensor revolution's plots (range m, bearing rad from +x towards +y,
    optional elevation rad and SNR dB) at time_s, the sensor at sensor_position_m."""
    s = pb.Scan(sequence=sequence, time_s=float(time_s), sensor_position_m=vector3(sensor_position_m))
    for i, (r, b) in enumerate(zip(ranges_m, bearings_rad)):
        d = s.detections.add(range_m=float(r), bearing_rad=float(b))
        if elevations_rad is not None:
            d.elevation_rad = float(elevations_rad[i])
        if snr_db is not None:
            d.snr_db = float(snr_db[i])
    return s
