"""What the service answers, as plain frozen dataclasses with SI units in the field names.

Why not the protobuf messages: a message has no "unset" for a position (a filter that has
no fix yet sends zeros), keeps covariances as flat lists and statuses as enum numbers. Here a
quantity the frame does not hold is None, vectors and matrices are read-only numpy arrays,
statuses are strings. Every object keeps the message it came from in ``raw`` (for fields
this layer does not map, or to forward it as is).

Coordinates are metres in the session's world frame (the frame of SessionConfig's
sensors_m), times seconds on the session clock (from its first audio sample).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._stubs import pb

__all__ = ["PairTdoa", "StageLatency", "Source", "PlatformPose", "Estimate", "Fix"]

_STATUS = {pb.TRACK_STATUS_TENTATIVE: "tentative", pb.TRACK_STATUS_CONFIRMED: "confirmed",
           pb.TRACK_STATUS_COASTING: "coasting"}


def _vec(v) -> np.ndarray:
    out = np.array([v.x, v.y, v.z])
    out.flags.writeable = False
    return out


def _matrix(values, n: int) -> np.ndarray | None:
    if len(values) != n * n:
        return None
    out = np.array(values, dtype=float).reshape(n, n)
    out.flags.writeable = False
    return out


@dataclass(frozen=True, slots=True)
class PairTdoa:
    """One sensor pair's measurement: (reference_sensor, sensor)."""
    sensor: int
    delay_s: float       # arrival at `sensor` minus arrival at the reference
    quality: float       # GCC peak / strongest sidelobe (> ~1.5: trustworthy)
    peak_snr: float      # GCC peak over its window's noise floor (Locate only; else 0)

    @classmethod
    def from_proto(cls, m: pb.PairTdoa) -> PairTdoa:
        return cls(m.sensor, m.delay_s, m.quality, m.peak_snr)


@dataclass(frozen=True, slots=True)
class StageLatency:
    """Server wall time spent on one estimate, seconds."""
    tdoa_s: float        # GCC-PHAT front end
    filter_s: float      # predict + update + estimate
    queue_s: float       # the completing block's wait for a worker
    total_s: float       # block received -> estimate ready

    @classmethod
    def from_proto(cls, m: pb.StageLatency) -> StageLatency:
        return cls(m.tdoa_s, m.filter_s, m.queue_s, m.total_s)


@dataclass(frozen=True, slots=True, eq=False)
class Source:
    """One source followed by direction (planar and linear arrays, direction sessions).

    Angles in the array's frame: azimuth atan2(y, x), elevation from the x-y plane towards
    +z; a linear array observes only ``cone_angle_rad`` (the others are NaN there).
    ``position_m`` / ``position_covariance`` (m, m^2) only where the frame bounds the range
    (localization "position"), else None."""
    id: int
    status: str                          # "tentative", "confirmed" or "coasting"
    direction: np.ndarray                # unit (x, y, z) from the array towards the source
    azimuth_rad: float
    elevation_rad: float
    cone_angle_rad: float
    sigma_rad: float                     # RMS angular standard deviation
    source_present: bool                 # a peak of this frame was assigned to it
    power_db: float                      # that peak over the noise level; NaN if none
    position_m: np.ndarray | None
    position_covariance: np.ndarray | None  # 3 x 3
    range_sd_m: float                    # NaN when no fit was made
    raw: pb.SourceDirection = field(repr=False)

    @classmethod
    def from_proto(cls, m: pb.SourceDirection) -> Source:
        has_position = m.HasField("position_m")
        return cls(id=m.source_id, status=_STATUS.get(m.status, "unspecified"),
                   direction=_vec(m.direction), azimuth_rad=m.azimuth_rad,
                   elevation_rad=m.elevation_rad, cone_angle_rad=m.cone_angle_rad,
                   sigma_rad=m.sigma_rad, source_present=m.source_present, power_db=m.power_db,
                   position_m=_vec(m.position_m) if has_position else None,
                   position_covariance=_matrix(m.position_covariance, 3) if has_position else None,
                   range_sd_m=m.range_sd_m, raw=m)


@dataclass(frozen=True, slots=True, eq=False)
class PlatformPose:
    """Moving arrays: the platform pose a frame's model used."""
    body_to_world: np.ndarray   # unit quaternion (w, x, y, z), body -> East-North-Up
    euler_rad: np.ndarray       # (roll, pitch, yaw); R = Rz(yaw) Ry(pitch) Rx(roll)
    euler_sd_rad: np.ndarray
    origin_m: np.ndarray        # body origin in the world

    @classmethod
    def from_proto(cls, m: pb.PlatformPose) -> PlatformPose:
        q = m.body_to_world
        quaternion = np.array([q.w, q.x, q.y, q.z])
        quaternion.flags.writeable = False
        return cls(quaternion, _vec(m.euler_rad), _vec(m.euler_sd_rad), _vec(m.origin_m))


@dataclass(frozen=True, slots=True, eq=False)
class Estimate:
    """One frame's estimate of a Track session.

    Position sessions: ``position_m`` (3,), ``velocity_mps`` (3,) and ``covariance`` (6 x 6
    over x, y, z, vx, vy, vz: m^2, m^2/s, m^2/s^2) once the filter has a fix
    (``initialised``), None before and in direction sessions. ``t_s``: reception instant at
    the reference sensor of the frame centre; the position is where the source emitted that
    sound. ``far_field``: the frame does not bound the range (trust the direction from the
    array's centroid; ``range_sd_m`` says by how much). ``ambiguous`` / ``modes``: several
    position hypotheses fit (the covariance covers them all). Direction sessions list their
    sources in ``sources``."""
    frame_index: int
    sequence: int                        # the block that completed this frame
    t_s: float
    initialised: bool
    reinitialised: bool
    position_m: np.ndarray | None
    velocity_mps: np.ndarray | None
    covariance: np.ndarray | None
    source_present: bool
    presence_statistic: float
    presence_threshold: float
    ambiguous: bool
    modes: int
    far_field: bool
    range_sd_m: float
    sources: tuple[Source, ...]
    pairs: tuple[PairTdoa, ...]
    pairs_used: int
    tdoa_sigma_s: float
    ess: float
    nis: float
    model_probabilities: dict[str, float]
    platform: PlatformPose | None
    latency: StageLatency
    backend: str
    raw: pb.Estimate = field(repr=False)

    @classmethod
    def from_proto(cls, m: pb.Estimate) -> Estimate:
        fixed = m.initialised
        return cls(
            frame_index=m.frame_index, sequence=m.sequence, t_s=m.t_s, initialised=fixed,
            reinitialised=m.reinitialised,
            position_m=_vec(m.position_m) if fixed else None,
            velocity_mps=_vec(m.velocity_mps) if fixed else None,
            covariance=_matrix(m.covariance, 6) if fixed else None,
            source_present=m.source_present, presence_statistic=m.presence_statistic,
            presence_threshold=m.presence_threshold, ambiguous=m.ambiguous, modes=m.modes,
            far_field=m.far_field, range_sd_m=m.range_sd_m,
            sources=tuple(Source.from_proto(s) for s in m.sources),
            pairs=tuple(PairTdoa.from_proto(p) for p in m.pairs), pairs_used=m.pairs_used,
            tdoa_sigma_s=m.tdoa_sigma_s, ess=m.ess, nis=m.nis,
            model_probabilities={p.model: p.probability for p in m.model_probabilities},
            platform=PlatformPose.from_proto(m.platform) if m.HasField("platform") else None,
            latency=StageLatency.from_proto(m.latency), backend=m.backend, raw=m)

    @property
    def position_sd_m(self) -> np.ndarray | None:
        """Standard deviations of x, y, z from the covariance's diagonal, m (None without)."""
        if self.covariance is None:
            return None
        return np.sqrt(np.clip(np.diag(self.covariance)[:3], 0.0, None))


@dataclass(frozen=True, slots=True, eq=False)
class Fix:
    """The answer of a one-shot Locate: every pair's TDOA and, if multilateration converged
    (``fix_found``), the position with its 3 x 3 covariance (m^2; the CRLB for the TDOA std
    the residuals show), else None."""
    pairs: tuple[PairTdoa, ...]
    fix_found: bool
    position_m: np.ndarray | None
    covariance: np.ndarray | None
    residual_rms_s: float                # RMS of measured minus modelled TDOAs
    gcc_wall_s: float                    # server wall time of the GCC stage
    raw: pb.LocateResponse = field(repr=False)

    @classmethod
    def from_proto(cls, m: pb.LocateResponse) -> Fix:
        found = m.fix_found
        return cls(pairs=tuple(PairTdoa.from_proto(p) for p in m.pairs), fix_found=found,
                   position_m=_vec(m.position_m) if found else None,
                   covariance=_matrix(m.covariance, 3) if found else None,
                   residual_rms_s=m.residual_rms_s,
                   gcc_wall_s=m.tdoa_s, raw=m)
