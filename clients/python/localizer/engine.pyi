"""localizer.engine: the localizer engine in-process, on numpy arrays (pybind11 bindings,
clients/python/engine_module).

    import numpy as np, localizer.engine as le
    scene = le.simulate_scenario("tetra-water", seed=1, duration_s=5.0)
    session = le.Session(scene["sensors_m"], scene["sample_rate_hz"],
                         sound_speed_mps=scene["sound_speed_mps"],
                         band_low_hz=scene["band_hz"][0], band_high_hz=scene["band_hz"][1], seed=1)
    frames = session.process(scene["samples"])      # one row per frame
    print(frames[frames["initialised"]][["t_s", "x_m", "y_m", "z_m", "sx_m"]])

Blocks are (samples, channels) arrays of float32 or float64, channel k = sensor k. An
F-ordered float32 block (e.g. ``localizer.audio.read(path)[0].T``, or a simulated scene's
``samples``) is already the engine's channel-major layout and is used without a copy; an
interleaved C-ordered one (e.g. ``soundfile.read(path, dtype="float32")[0]``) is converted.

Estimates are numpy structured arrays, one row per frame (``estimate_dtype``): the fields of
the CLI's estimates.csv under the engine's names, SI units in the names. Errors: the engine's
INVALID_ARGUMENT raises ValueError, any other code RuntimeError (message "CODE: ..."); a
wrong shape or dtype is a ValueError, an unknown option or a value of the wrong type a
TypeError. The engine runs without the GIL: sessions in different threads run in parallel.
Options follow localizer-cli's flags (clients/cli/session_flags.cc) so that the same options
give the same estimates as ``localizer-cli track``.
"""
from typing import Any, Literal, Sequence, TypedDict, overload

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
Vec3 = Sequence[float] | npt.NDArray[np.float64]

# Session ------------------------------------------------------------------------------------

class Session:
    """An audio tracking session (engine::Session, engine/pipeline/session.h).

    sensors_m: (N, 3) metres; sample_rate_hz > 0. Options (keyword, None = the default;
    ``Session.default_options()`` lists them with their values): the fields of
    engine::AudioSessionConfig under the same names, except filter (tracker.kind), particles,
    likelihood, outlier_probability, tdoa_sigma_s (0: adaptive), max_sources (0: not stated), accel_noise_mps2 and the
    accel_level_* / manoeuvre_* particle options (tracker.particle.*), motion_model and
    robust (tracker.kalman.*), imm_modes ("cv,ct"), imm_variant. As the CLI: accel_noise_mps2
    and tdoa_sigma_s drive every filter kind, and frame_samples / hop_samples default to
    4096 / 2048, or to about 32 ms / half of it for sessions that list sources.
    Moving arrays (array_in_body_frame, IMU samples) are not bound.
    """

    def __init__(self, sensors_m: ArrayLike, sample_rate_hz: float, *,
                 sound_speed_mps: float = 1500.0, reference_sensor: int = 0,
                 frame_samples: int | None = None, hop_samples: int | None = None,
                 max_block_samples: int = 4194304,
                 weighting: str = "phat", phat_beta: float = 0.8,
                 band_low_hz: float = 0.0, band_high_hz: float = 0.0, despike_k: float = 5.0,
                 filter: str = "pf", motion_model: str = "cv", imm_modes: str = "cv,ct",
                 imm_variant: str = "ekf", robust: str = "none", particles: int = 4096,
                 likelihood: str = "peak", outlier_probability: float = 0.05,
                 tdoa_sigma_s: float = 0.0, accel_noise_mps2: float = 1.0,
                 manoeuvre_share: float = 0.0, manoeuvre_scale: float = 10.0,
                 accel_level_floor: float = 0.003, accel_level_ceiling: float = 3.0,
                 accel_level_switch_hz: float = 1.0, turn_rate_max_radps: float = 1.0,
                 speed_change_max_mps2: float = 1.0, seed: int = 1,
                 init_speed_sigma_mps: float = 2.0,
                 init_region_min_m: Vec3 | None = None, init_region_max_m: Vec3 | None = None,
                 divergence_window: int = 8,
                 bounds_min_m: Vec3 | None = None, bounds_max_m: Vec3 | None = None,
                 search_radius_m: float = 0.0, presence_false_alarm: float = 0.001,
                 source_timeout_s: float = 2.0,
                 localization: Literal["auto", "position", "direction"] = "auto",
                 max_sources: int = 0, source_side: Vec3 | None = None,
                 source_plane_point_m: Vec3 | None = None, source_plane_normal: Vec3 | None = None,
                 backend: Literal["cpu", "gpu", "auto"] = "cpu",
                 direction_present_hold_s: float = 0.05, direction_diffuse_weighting: bool = True,
                 direction_signal_weighting: bool | None = None) -> None: ...

    @overload
    def process(self, block: ArrayLike, with_sources: Literal[False] = False) -> np.ndarray:
        """Validates and consumes one (samples, channels) block; the frames it completed
        (structured array, ``estimate_dtype``). A rejected block (ValueError: wrong channel
        count, empty, non-finite sample, ...) leaves the session as it was."""
    @overload
    def process(self, block: ArrayLike, with_sources: Literal[True]) -> tuple[np.ndarray, np.ndarray]:
        """As above, plus every frame's sources (``source_dtype``; sessions that list sources)."""
    def skip(self, samples_per_channel: int) -> None:
        """The stream lost this many samples per channel before the next block."""
    @property
    def config(self) -> dict[str, Any]:
        """The config the session resolved, under the option names, plus sensors_m and
        sample_rate_hz; localization with auto resolved."""
    @property
    def localization(self) -> Literal["position", "direction"]: ...
    @property
    def reports_sources(self) -> bool: ...
    @property
    def backend(self) -> str: ...
    @property
    def sensor_count(self) -> int: ...
    @property
    def pair_count(self) -> int:
        """Pairs (reference, k) of a position session (sensors - 1); 0 when it lists sources."""
    @property
    def frames_processed(self) -> int: ...
    @property
    def estimate_dtype(self) -> np.dtype: ...
    @staticmethod
    def default_options() -> dict[str, Any]: ...

def estimate_dtype(pair_count: int) -> np.dtype:
    """A frame row: frame_index, sequence (u8); t_s, x_m, y_m, z_m, vx_mps, vy_mps, vz_mps,
    sx_m, sy_m, sz_m (sqrt of the covariance diagonal), presence_statistic,
    presence_threshold, range_sd_m, ess, nis, tdoa_sigma_s, tdoa_wall_s, filter_wall_s (f8);
    initialised, reinitialised, source_present, ambiguous, far_field (bool); modes,
    pairs_used (i4); covariance (6, 6); with pair_count > 0 delay_s and quality
    (pair_count,) per pair (reference, k), NaN before a frame measured them."""

def source_dtype() -> np.dtype:
    """A source row: frame_index, t_s, source_id, status ("tentative" | "confirmed" |
    "coasting"), source_present, azimuth_rad, elevation_rad, cone_angle_rad, sigma_rad,
    power_db, direction (3,), position_m (3,), range_sd_m (NaN where the array cannot say)."""

# TDOA ---------------------------------------------------------------------------------------

class PairDelay(TypedDict):
    delay_s: float        # t_arrival(other) - t_arrival(reference)
    delay_samples: float  # delay_s * sample_rate_hz
    quality: float        # peak over the largest sidelobe (small, even < 1: no clear peak)
    peak_value: float     # GCC at the peak (PHAT: 1 for a perfect single path)
    peak_snr: float
    delay_sigma_s: float

def gcc_phat_pair(reference: ArrayLike, other: ArrayLike, sample_rate_hz: float,
                  max_delay_s: float, *, weighting: str = "phat", phat_beta: float = 0.8,
                  band_low_hz: float = 0.0, band_high_hz: float = 0.0) -> PairDelay:
    """GCC-PHAT of two 1-D channels of one length (64 to 2^20 samples), the peak searched
    within +-max_delay_s (plus 2 samples) and refined below a sample."""

def gcc_phat(frame: ArrayLike, sensors_m: ArrayLike, sample_rate_hz: float, *,
             sound_speed_mps: float = 1500.0, reference_sensor: int = 0, weighting: str = "phat",
             phat_beta: float = 0.8, band_low_hz: float = 0.0,
             band_high_hz: float = 0.0) -> np.ndarray:
    """Every pair (reference, k) of one (samples, channels) frame of a 3-D array (4 or more
    sensors off a plane): rows sensor, delay_s, delay_samples, quality, peak_value, peak_snr,
    delay_sigma_s."""

class Fix(TypedDict):
    position_m: npt.NDArray[np.float64]     # (3,)
    covariance_m2: npt.NDArray[np.float64]  # (3, 3), the CRLB at the fix for tdoa_sigma_s
    position_std_m: float
    rms_residual_s: float
    iterations: int
    converged: bool

def multilaterate(sensors_m: ArrayLike, tdoa_s: ArrayLike, *, sound_speed_mps: float = 1500.0,
                  reference_sensor: int = 0, tdoa_sigma_s: float = 2e-05,
                  max_iterations: int = 50, hint_m: Vec3 | None = None) -> Fix:
    """A position from one TDOA per pair (reference, k), k ascending (closed form, then
    Levenberg-Marquardt). RuntimeError (FAILED_PRECONDITION) when nothing converges."""

def model_tdoa(sensors_m: ArrayLike, source_m: Vec3, *, sound_speed_mps: float = 1500.0,
               reference_sensor: int = 0) -> npt.NDArray[np.float64]:
    """The engine's TDOA model: (|s - m_k| - |s - m_ref|) / c per pair, seconds."""

# Simulator ----------------------------------------------------------------------------------

class Scene(TypedDict, total=False):
    name: str
    description: str
    samples: npt.NDArray[np.float32]  # (samples, channels), F order (channel-major memory)
    sample_rate_hz: float
    sensors_m: npt.NDArray[np.float64]  # (channels, 3)
    sound_speed_mps: float
    reference_sensor: int
    band_hz: tuple[float, float]      # the source's band
    snr_db: float
    seed: int
    truth: np.ndarray  # t_s, x_m, y_m, z_m, vx_mps, vy_mps, vz_mps per truth step
    scene_class: str   # random scenes: gaussian | multipath | impulsive
    medium: str        # random scenes: water | air
    aperture_m: float
    start_range_m: float

def scenario_names() -> list[str]: ...
def simulate_scenario(name: str, seed: int = 1, *, duration_s: float | None = None,
                      snr_db: float | None = None) -> Scene:
    """A named scenario (tetra-water, tetra-air, turn-multipath, clicks-water) rendered as
    ``localizer-cli simulate --scenario NAME --seed SEED`` renders it."""
def simulate_random_scene(seed: int, *, duration_s: float = 12.0,
                          scene_class: str | None = None) -> Scene:
    """A scene drawn at random from the seed (engine/sim/random_scene.h), rendered."""

# Attitude -----------------------------------------------------------------------------------

class AttitudeFilter:
    """The platform attitude filter (engine/attitude/attitude_filter.h). kind: "quaternion"
    | "euler". Further keyword options: the numeric fields of AttitudeFilterOptions
    (gravity_mps2, gyro_noise_rps_rthz, accel_tilt_sd_rad, ...)."""
    def __init__(self, kind: str = "quaternion", use_mag: bool = False, **options: float) -> None: ...
    def update(self, t_s: ArrayLike, gyro_rps: ArrayLike, accel_mps2: ArrayLike,
               mag_uT: ArrayLike | None = None) -> np.ndarray:
        """N samples in time order (t_s (N,), gyro_rps, accel_mps2, mag_uT (N, 3)), all
        checked before any is applied -> one row per sample: t_s, quaternion (w, x, y, z)
        body -> world, euler_rad (roll, pitch, yaw), sd_rad, gyro_bias_rps, initialised,
        accel_used, mag_used, at_rest."""

# Track-while-scan ---------------------------------------------------------------------------

class ScanSummary(TypedDict):
    plots: int
    assigned: int
    initiated: int
    deleted: int
    confirmed: int
    tentative: int

class TwsTracker:
    """Track-while-scan multi-target tracker (engine/tws/tws_tracker.h). Keyword options:
    dimensions (2), range_sigma_m, bearing_sigma_rad, elevation_sigma_rad, accel_noise_mps2,
    gate_probability, confirm_hits, confirm_window, max_coast_scans, max_position_sigma_m,
    initial_speed_sigma_mps, max_speed_mps, max_tracks (tws_options.h's defaults)."""
    def __init__(self, **options: float) -> None: ...
    def process_scan(self, time_s: float, range_m: ArrayLike, bearing_rad: ArrayLike,
                     elevation_rad: ArrayLike | None = None,
                     sensor_position_m: Vec3 = (0.0, 0.0, 0.0)) -> ScanSummary:
        """One scan of polar plots (bearing from +x towards +y)."""
    def process_cartesian(self, time_s: float, positions_m: ArrayLike,
                          covariances_m2: ArrayLike) -> ScanSummary:
        """One scan of Cartesian plots: positions (N, 3), covariances (N, 3, 3)."""
    def tracks(self, include_tentative: bool = True) -> np.ndarray:
        """Rows id, status, position_m (3,), velocity_mps (3,), covariance (6, 6), hits,
        consecutive_misses, time_s."""
