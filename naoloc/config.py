"""Typed configuration: every key (listed in docs/cli.md) with a default, unknown keys rejected.

A config comes from a YAML file (read with a bounded ``yaml.SafeLoader`` only, see
:mod:`naoloc.safe_yaml`: size, nesting, alias expansion and integer digits capped), a
dict, or a :class:`Config`. Every number must be finite. Errors are one line naming the
file and the key path, e.g. ``configs/x.yaml: world.room.sise_m: unknown key``.
"""

from __future__ import annotations

import difflib
import enum
import logging
import math
import typing
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, SecretStr, ValidationError, field_validator

from naoloc.constants import CAMERA_FPS, COLORSPACE_LAYERS, RESOLUTIONS
from naoloc.errors import ConfigError
from naoloc.safe_yaml import MAX_CONFIG_BYTES, check_values, load_yaml, read_text, short_repr

__all__ = ["MAX_CONFIG_BYTES", "Config", "load_config"]


class _Model(BaseModel):
    model_config = ConfigDict(
        extra="forbid", frozen=True, validate_default=True, allow_inf_nan=False
    )


class RobotConfig(_Model):
    """Which robot to talk to."""

    backend: Literal["mujoco", "naoqi", "fake"] = Field(
        "mujoco", description="mujoco (simulator), naoqi (network) or fake (unit tests)"
    )
    url: str = Field("tcp://127.0.0.1:9559", description="NAOqi address; naoqi backend only")
    transport: Literal["auto", "libqi", "zmq", "qimessaging"] = Field(
        "auto",
        description="naoqi only: libqi (real qi package), zmq (our shim), "
        "qimessaging (libqi's protocol in pure Python), auto",
    )
    user: str | None = Field(None, description="NAOqi 2.9+ (tcps://) user, usually 'nao'")
    password: SecretStr | None = Field(
        None, description="NAOqi 2.9+ (tcps://) password; never written to any file"
    )
    timeout_s: float = Field(5.0, gt=0, le=3600, description="timeout of one remote call (s)")
    move_timeout_s: float = Field(
        300.0, gt=0, description="naoqi only: timeout of one blocking motion call, seconds"
    )
    sim_service: bool = Field(
        False, description="naoqi only: expose the virtual NAOqi's NaolocSim as robot.sim"
    )
    curve_keys: str | None = Field(
        None, description="zmq transport: folder of CURVE certificates (needed off loopback)"
    )
    tls_trust: str | None = Field(
        None, description="qimessaging tcps://: null (pin first use), sha256:HEX, a PEM, insecure"
    )


class RoomChanges(_Model):
    """What changed in the room since it was surveyed (the Microsoft indoor-localization
    competition moved furniture between set-up and test).

    Applied to the generated room (``world.room.changes``): a map built from a survey of the
    room without changes is then localized against in the changed one
    (``evaluate --protocol changed``).
    """

    moved: float = Field(
        0.3, ge=0, le=1, description="share of the furniture moved (rounded to whole pieces)"
    )
    max_move_m: float = Field(
        0.5, ge=0, le=3.0, description="farthest a moved piece goes, in x and y (m)"
    )
    added: int = Field(
        2, ge=0, le=20, description="boxes added that the survey never saw (0.3-0.6 m)"
    )
    seed: int = Field(0, ge=0, description="seed of which pieces move, where, and the boxes")


class RoomConfig(_Model):
    """A procedurally generated room (simulated backends)."""

    size_m: tuple[float, float] = Field((6.0, 6.0), description="inner size along x, y (m)")
    wall_height_m: float = Field(2.5, gt=0.5, le=10.0, description="wall height (m)")
    seed: int = Field(0, ge=0, description="seed of posters, textures and furniture")
    posters_per_wall: int = Field(5, ge=0, le=50, description="posters on each wall")
    furniture: bool = Field(True, description="tables, chairs, shelves from primitives")
    style: Literal["home", "office", "posters"] = Field(
        "home",
        description="home/office: art at real heights (1.2-1.8 m), skirting, doors, windows, "
        "radiators; posters: posters in the camera's band (the rooms of earlier versions)",
    )
    poster_dir: str | None = Field(
        None, description="folder of photographs to use as posters instead of procedural ones"
    )
    changes: RoomChanges | None = Field(
        None, description="furniture moved or added since the survey; null = none"
    )

    @field_validator("size_m")
    @classmethod
    def _size_ok(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not all(1.5 <= s <= 50.0 for s in v):
            raise ValueError("each side must be between 1.5 and 50 m")
        return v


class OdometryConfig(_Model):
    """Odometry error of simulated backends: how far the true walk strays from odometry.

    ``profile: nao`` draws per-run systematic errors from ``seed`` at the magnitudes of
    published NAO figures (see ``naoloc/backends/simulated/odometry.py`` for the sources);
    ``profile: ideal`` is exact. Any key set here overrides the profile's value (a set
    ``scale_error`` or ``turn_scale_error`` is used as is instead of being drawn).
    """

    profile: Literal["nao", "ideal"] = Field(
        "nao", description="nao (published NAO drift) | ideal (exact, for unit tests)"
    )
    scale_error: float | None = Field(
        None, ge=-0.5, le=0.5, description="odometry reads (1 + e) times the true distance"
    )
    turn_scale_error: float | None = Field(
        None, ge=-0.5, le=0.5, description="odometry reads (1 + e) times the true turn"
    )
    heading_bias_rad_per_m: float | None = Field(
        None, description="odometry heading error per metre walked (rad/m)"
    )
    random_walk_m_per_sqrt_m: float | None = Field(
        None, ge=0, description="position noise std per sqrt(metre) walked"
    )
    heading_random_walk_rad_per_sqrt_m: float | None = Field(
        None, ge=0, description="heading noise std per sqrt(metre) walked"
    )
    heading_random_walk_rad_per_sqrt_rad: float | None = Field(
        None, ge=0, description="heading noise std per sqrt(radian) turned (feet slip)"
    )
    turn_slip_m_per_sqrt_rad: float | None = Field(
        None, ge=0, description="position noise std per sqrt(radian) turned (feet slip)"
    )
    level: float = Field(
        1.0, ge=0, le=20, description="multiplies every error magnitude (robustness studies)"
    )
    seed: int = Field(0, ge=0, description="seed of the per-run errors and the noise")


class CameraRealismConfig(_Model):
    """Image formation of simulated cameras (``naoloc/backends/simulated/camera_model.py``).

    ``profile: nao`` models a NAO's camera: sensor noise (SNR at most 37 dB, more at high
    gain), auto exposure and auto white balance, vignetting, YUV422 chroma, NAO's lens
    calibration, motion blur. ``profile: ideal`` gives the clean rendered frames. A key left
    at ``null`` takes the profile's value; an explicit value overrides the profile.
    """

    profile: Literal["nao", "ideal"] = Field(
        "nao", description="nao (a NAO's camera) | ideal (clean frames, for unit tests)"
    )
    noise_std: float | None = Field(
        None,
        ge=0,
        le=64,
        description="Gaussian pixel noise std, 0-255 units; null = profile "
        "(nao: shot and read noise of the sensor at its gain)",
    )
    blur_px: float | None = Field(
        None, ge=0, le=10, description="extra Gaussian blur sigma in pixels; null = profile"
    )
    exposure: float | None = Field(
        None,
        gt=0,
        le=16,
        description="fixed brightness gain (turns auto exposure off); "
        "null = profile (nao: auto exposure)",
    )
    jpeg_quality: int | None = Field(
        None, ge=5, le=100, description="JPEG round trip quality; null = none"
    )
    auto_white_balance: bool | None = Field(None, description="gray-world AWB; null = profile")
    vignetting: float | None = Field(
        None, ge=0, lt=1, description="brightness loss in the image corners; null = profile"
    )
    yuv422: bool | None = Field(None, description="chroma halved horizontally; null = profile")
    distortion: bool | None = Field(
        None, description="NAO's lens calibration (k1, focal, principal point); null = profile"
    )
    motion_blur: bool | None = Field(
        None, description="blur along the camera's motion during the exposure; null = profile"
    )
    rolling_shutter: bool = Field(False, description="rows exposed one after another")
    ae_target: float = Field(
        110.0, gt=10, lt=245, description="auto exposure's target mean luma, 0-255"
    )
    seed: int = Field(0, ge=0, description="seed of the noise")

    def pick(self, value: bool | None) -> bool:
        """A switch of this block: its explicit value, or the profile's (on for ``nao``)."""
        return self.profile == "nao" if value is None else bool(value)

    @property
    def lens_distortion(self) -> bool:
        """Whether simulated pictures carry NAO's lens distortion (``distortion`` or profile)."""
        return self.pick(self.distortion)


class SimConfig(_Model):
    """Simulator settings."""

    timestep_s: float = Field(0.005, ge=0.001, le=0.05, description="physics step (s)")
    realtime: bool = Field(False, description="pace simulated time to the wall clock")
    light: float = Field(1.0, gt=0, le=4, description="scale of the room lights' intensity")
    seed: int = Field(0, ge=0, description="seed of the simulator's own randomness")
    start_awake: bool = Field(
        True,
        description="start standing in StandInit with motors on (as Webots' NAO does); "
        "false = at rest in Crouch, motors off, like a NAO just switched on",
    )
    camera_sway: bool = Field(
        True, description="torso and head sway and bob while walking, as on a NAO"
    )


class WorldConfig(_Model):
    """The simulated world: room, robot model, start pose, realism."""

    room: RoomConfig = RoomConfig()
    start_pose: tuple[float, float, float] | None = Field(
        None,
        description="room frame x, y (m), theta (rad); default: survey.wall_offset_m from "
        "the two walls at the room-frame origin, facing +x",
    )
    model: Literal["v5", "v6"] = Field("v5", description="NAO head: field of view of V5 or V6")
    odometry: OdometryConfig = OdometryConfig()
    camera_realism: CameraRealismConfig = CameraRealismConfig()
    sim: SimConfig = SimConfig()


def _resolution_id(v: int) -> int:
    """``v`` when it is a NAOqi resolution id, else ValueError naming the valid ones."""
    if v not in RESOLUTIONS:
        raise ValueError(f"unknown resolution id {v}; valid: {sorted(RESOLUTIONS)}")
    return v


class FloorLineTuning(_Model):
    """Thresholds of the floor-wall line detector (naoloc.perception.floorline).

    Distances in metres on the floor (FRAME_ROBOT), angles in radians; colours in the
    detector's weighted CIE Lab (lightness scaled by 0.3) or chromaticity (channel shares).
    """

    min_inliers: int = Field(
        12, ge=2, description="least boundary pixels on a line (RANSAC's best and each refit)"
    )
    min_inlier_fraction: float = Field(
        0.5,
        ge=0,
        le=1,
        description="least share of the boundary pixels left to it that a line after the "
        "image's best needs (every line needs half of this)",
    )
    min_span_m: float = Field(
        0.3, ge=0, description="least length of the line its inliers cover (m)"
    )
    ransac_tolerance_m: float = Field(
        0.03, gt=0, description="largest distance of an inlier from the line (m)"
    )
    ransac_samples: int = Field(
        200, ge=1, le=10000, description="random point pairs a line's RANSAC tries"
    )
    max_range_m: float = Field(
        4.0,
        gt=0,
        description="floor points farther than this from the camera's foot are dropped (m)",
    )
    tone_ratio: tuple[float, float] = Field(
        (0.75, 1.45),
        description="lightness of a board of the same floor against the floor's (ratio, low "
        "and high): planks' tones vary",
    )
    darkest_foot: float = Field(
        0.7,
        ge=0,
        le=1,
        description="a pixel at the wall's foot darker than this share of the floor's "
        "lightness is not floor",
    )
    chroma_tol: tuple[float, float] = Field(
        (0.008, 0.02),
        description="chromaticity distance of the same floor's boards (bounds of the "
        "sample's own spread, channel shares)",
    )
    ghost_ratio: tuple[float, float] = Field(
        (1.04, 1.4),
        description="a skirting board's top edge (0.08-0.12 m up) projected to the floor "
        "from a camera 0.4-0.5 m up stands 1.1-1.35 times as far as the wall's foot (measured: "
        "1.10-1.27, RESULTS stop 49): a farther parallel line within this ratio (low, high) "
        "may be that ghost",
    )
    ghost_band_share: float = Field(
        0.5,
        ge=0,
        description="the far line's band moved more than this share of the way from the "
        "floor's colour to the board's is the board (a skirting ghost)",
    )
    ghost_min_step: float = Field(
        2.0,
        gt=0,
        description="... in a channel (weighted Lab) in which the board and floor differ by "
        "this or more",
    )
    ghost_parallel_rad: float = Field(
        0.3,
        ge=0,
        le=math.pi,
        description="lines within this angle are a foot and its board's edge (rad): a "
        "board's edge runs along its foot; a short ghost's fit turns 0.3 rad",
    )

    @field_validator("tone_ratio", "ghost_ratio")
    @classmethod
    def _ratio_ok(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not 0 < v[0] < v[1]:
            raise ValueError("must be [low, high] with 0 < low < high")
        return v

    @field_validator("chroma_tol")
    @classmethod
    def _clip_ok(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not 0 <= v[0] <= v[1]:
            raise ValueError("must be [low, high] with 0 <= low <= high")
        return v


class CameraConfig(_Model):
    """Which camera and image format behaviours subscribe to."""

    index: int = Field(0, ge=0, le=1, description="0 top, 1 bottom")
    resolution: int = Field(1, description="NAOqi resolution id (1 = kQVGA 320x240)")
    colorspace: int = Field(11, description="NAOqi colorspace id (11 = kRGB)")
    fps: int = Field(30, description="5, 10, 15 or 30")
    lens: Literal["auto", "nao", "pinhole"] = Field(
        "auto",
        description="the lens naoloc undoes (floor lines, keypoints): nao = NAO's calibrated "
        "top camera (fx 557 px at VGA, principal point (309, 231), k1 -0.055), pinhole = none; "
        "auto = nao unless world.camera_realism turns lens distortion off",
    )
    floor_lines: FloorLineTuning = Field(
        FloorLineTuning(),
        description="the floor-wall line detector's thresholds (naoloc.perception.floorline)",
    )

    @field_validator("resolution")
    @classmethod
    def _res_ok(cls, v: int) -> int:
        return _resolution_id(v)

    @field_validator("colorspace")
    @classmethod
    def _cs_ok(cls, v: int) -> int:
        if v not in COLORSPACE_LAYERS:
            raise ValueError(f"unknown colorspace id {v}; valid: {sorted(COLORSPACE_LAYERS)}")
        return v

    @field_validator("fps")
    @classmethod
    def _fps_ok(cls, v: int) -> int:
        if v not in CAMERA_FPS:
            raise ValueError(f"fps must be one of {list(CAMERA_FPS)}")
        return v


class SurveyConfig(_Model):
    """Algorithm 3: closed laps of a rectangle along the walls."""

    laps: int = Field(2, ge=1, le=20, description="closed laps")
    step_m: float = Field(0.2, gt=0.01, le=2.0, description="distance between pictures (m)")
    wall_offset_m: float = Field(
        1.0,
        gt=0.2,
        description="circuit's distance from the walls (m); 0.5 or more (nearer, the bottom "
        "camera cannot see the wall's foot beside the robot: the survey refuses it); below "
        "0.6 the robot keeps 0.6 m from the walls, the circuit's sides as configured",
    )
    side_m: tuple[float, float] | None = Field(
        None,
        description="[along x, along y] sides of the circuit (m); null = room size - 2 * offset",
    )
    skirting_m: float | None = Field(
        None,
        ge=0.0,
        le=0.1,
        description="how far the skirting boards stand out of the walls (m): the floor line "
        "sees their face, the room and the map's walls are measured wall to wall (0: none); "
        "null: 0.012, or 0 in a simulated room without boards (style posters, the fake robot)",
    )
    head_yaw_rad: float | None = Field(
        None, description="head yaw while walking; null = from the nearest-wall detector"
    )
    look_ahead_rad: float = Field(
        0.77,
        ge=0.0,
        le=1.2,
        description="pictures are taken with the head turned this far from the side wall "
        "toward the walking direction (0 = straight at the wall, as in the paper); at 0.77 "
        "the top camera sees the art hung above its band at 1 m; the floor-wall line is "
        "still measured facing the wall",
    )
    head_pitch_rad: float = Field(
        -0.672,
        ge=-0.672,
        le=0.515,
        description="head pitch of the survey's pictures (rad, negative looks up; clamped to "
        "the head's limits at its yaw): up toward the art at 1.2-1.8 m",
    )
    far_yaws_rad: tuple[float, ...] = Field(
        (0.0, 1.3),
        max_length=8,
        description="head yaws of the far pictures (rad from the walking direction toward the "
        "room's interior; 0 = the wall ahead): after each stop's wall picture the survey "
        "also photographs the room across its interior, far_per_stop pictures at these yaws "
        "in turn, so the map sees every wall from 1-7 m as well as from the circuit; [] = "
        "none (the paper's survey). Only the verified localizer uses them: the paper's "
        "vocabulary and GCS learn the wall pictures alone",
    )
    far_per_stop: int = Field(
        1, ge=1, le=8, description="far pictures taken at each stop (cycling through far_yaws_rad)"
    )
    far_pitch_rad: float = Field(
        -0.3,
        ge=-0.672,
        le=0.515,
        description="head pitch of the far pictures (rad): the art at 1.2-1.8 m on walls 2-7 m "
        "away sits 8-15 deg above the camera, which the wall pictures' pitch leaves out",
    )


# --- Map building and localizing tuning (naoloc.mapping): defaults are the tuned values. ---


class LandmarkTuning(_Model):
    """Triangulation of landmarks between nearby keyframes (naoloc.mapping.landmarks)."""

    pair_min_baseline_m: float = Field(
        0.05, gt=0, description="least camera baseline of a pair (m)"
    )
    pair_max_baseline_m: float = Field(
        1.2, gt=0, description="largest camera baseline of a pair (m)"
    )
    pair_max_view_angle_deg: float = Field(
        50.0, gt=0, le=180, description="largest angle between the views of a pair (deg)"
    )
    pairs_per_keyframe: int = Field(4, ge=1, description="pairs per keyframe, nearest first")
    ratio_test: float = Field(0.8, gt=0, le=1, description="Lowe ratio of descriptor matches")
    max_reprojection_px: float = Field(
        2.0,
        gt=0,
        description="largest reprojection error of a triangulated point in either view (px)",
    )
    epipolar_px: float = Field(3.0, gt=0, description="largest distance to the epipolar line (px)")
    min_parallax_deg: float = Field(1.0, ge=0, description="least parallax of a point (deg)")
    depth_range_m: tuple[float, float] = Field(
        (0.15, 12.0), description="depth range of a point in both cameras (m)"
    )


class PoseGraphTuning(_Model):
    """Survey pose refinement by visual loop closures (naoloc.mapping.posegraph)."""

    local_window: int = Field(
        3, ge=1, description="keyframes either side triangulating local landmarks"
    )
    loop_min_gap: int = Field(
        6, ge=1, description="keyframes closer in capture order are tied by odometry only"
    )
    loop_candidates: int = Field(3, ge=1, description="retrieval candidates per keyframe")
    geometric_candidates: int = Field(
        3, ge=0, description="candidates per keyframe from the first solution's camera poses"
    )
    loop_min_inliers: int = Field(15, ge=4, description="least PnP inliers of a loop closure")
    sigma_odo_xy: tuple[float, float] = Field(
        (0.002, 0.01),
        description="odometry position noise per edge: constant (m), per metre walked",
    )
    sigma_odo_theta: tuple[float, float, float] = Field(
        (0.001, 0.006, 0.002),
        description="odometry heading noise per edge: constant (rad), per sqrt(rad) turned, "
        "per metre walked (rad/m)",
    )
    loop_reprojection_px: float = Field(
        3.0, gt=0, description="inlier threshold of loop-closure PnP (px)"
    )
    loop_pixel_sigma: float = Field(
        1.0, gt=0, description="least pixel noise of a loop-closure match (px)"
    )
    loop_effective_matches: int = Field(
        20,
        ge=1,
        description="matches counted at most per loop closure (their landmark errors correlate)",
    )
    huber_k: float = Field(
        2.0, gt=0, description="loop residuals beyond this many sigmas get a linear loss"
    )
    sigma_bias_prior: float = Field(
        0.05, gt=0, description="prior of the odometry heading bias around 0 (rad/m)"
    )
    outlier_chi2: float = Field(
        16.0, gt=0, description="loop closures with a larger chi-square are dropped"
    )
    geometric_max_angle_deg: float = Field(
        45.0, gt=0, le=180, description="largest angle between views of a geometric pair (deg)"
    )
    geometric_lookahead_m: float = Field(
        1.5, gt=0, description="look-at point ahead of a camera (m)"
    )
    geometric_max_distance_m: float = Field(
        1.0, gt=0, description="largest distance between look-at points (m)"
    )
    max_height_change_m: float = Field(
        0.1, gt=0, description="largest height between the robots of a loop closure (same floor, m)"
    )


class BundleTuning(_Model):
    """Bundle adjustment of poses and landmarks (naoloc.mapping.bundle)."""

    pixel_sigma_px: float = Field(1.0, gt=0, description="pixel noise of an observation (px)")
    huber_px: float = Field(
        2.0, gt=0, description="reprojection errors beyond this get a linear loss (px)"
    )
    max_error_px: float = Field(
        8.0, gt=0, description="observations beyond this after an iteration are dropped (px)"
    )
    min_track: int = Field(2, ge=2, description="least keyframes seeing a track")
    long_track_gap: int = Field(
        6,
        ge=1,
        description="capture-index span of a long track (build-map uses half the loop gap)",
    )
    min_long_tracks: int = Field(
        50,
        ge=0,
        description="below this many lap-tying tracks the adjustment keeps the loop closures",
    )
    min_depth_m: float = Field(
        0.05, gt=0, description="points nearer the camera than this are not used (m)"
    )
    iterations: int = Field(6, ge=1, description="Levenberg-Marquardt iterations at most")
    lm_lambda: tuple[float, float, float] = Field(
        (1e-3, 1e-7, 1e4),
        description="Levenberg-Marquardt damping: start, least, largest (gives up)",
    )
    wall_prior_sigma: tuple[float, float] | None = Field(
        (0.1, 0.01),
        description="hold wall-referenced keyframe poses near where the walls put them: "
        "position (m), heading (rad); null = no such prior",
    )


class MapCheckTuning(_Model):
    """Limits of build-map's checks of a survey's map frame (naoloc.mapping.checks)."""

    min_corner_share: float = Field(
        0.75, ge=0, le=1, description="least share of the circuit's corners a wall placed"
    )
    max_origin_heading_deg: float = Field(
        4.0,
        gt=0,
        description="largest difference between the start's heading from its own lines and "
        "from its first steps' (deg); the steps' carry the odometry's turn, about 1.7 deg "
        "(one std) over their first half metre",
    )
    min_coverage: float = Field(
        0.7, ge=0, le=1, description="least share of each wall's stops with its floor line"
    )
    max_wall_fit_m: float = Field(
        0.06,
        gt=0,
        description="largest RMS of the side lines' change between stops against the "
        "odometry's walk away from the wall (m)",
    )
    max_lap_difference_pct: float = Field(
        20.0,
        gt=0,
        description="largest lap-to-lap difference of a side's metres per odometry metre (%): "
        "a NAO's odometry alone varies 5-15 % between laps",
    )
    odometry_scale_range: tuple[float, float] = Field(
        (0.75, 1.33), description="a side's metres per odometry metre a NAO's walk can give"
    )
    max_size_error_pct: float = Field(
        12.0,
        gt=0,
        description="largest disagreement of the configured sides along x with those along y, "
        "by the metres per odometry metre each implies (%)",
    )
    max_lap_disagreement_m: float = Field(
        0.1,
        gt=0,
        description="largest distance, over a side of a later lap, between its pictures' "
        "map poses and where the first lap's landmarks put them (their precision-weighted "
        "mean offset, m)",
    )
    lap_view_radius_m: float = Field(
        0.6, gt=0, description="first-lap pictures within this of a later one are its views (m)"
    )
    lap_view_angle_deg: float = Field(
        30.0, gt=0, le=90, description="and whose view is within this angle of its (deg)"
    )
    lap_pnp_inliers: int = Field(
        12, ge=6, description="PnP inliers that place a later picture on the first lap's landmarks"
    )
    lap_pnp_px: float = Field(4.0, gt=0, description="that PnP's RANSAC inlier threshold (px)")
    lap_min_frames: int = Field(
        3, ge=1, description="placed pictures a later side needs for its offset to count"
    )
    lap_pixel_sigma_px: float = Field(
        2.0, gt=0, description="a placed picture's reprojection error (px, std; measured 1.5-2.4)"
    )
    lap_floor_m: float = Field(
        0.02,
        ge=0,
        description="error every placement carries besides its fit's: the first lap's "
        "landmarks' own (m, std)",
    )


class WallPoseTuning(_Model):
    """The survey keyframes' poses from the walls' floor lines (naoloc.mapping.wall_poses).

    Tunes :func:`naoloc.mapping.wall_poses.wall_poses`: which side lines it believes (and
    which see furniture before the wall), which front lines place a side's end, and how it
    finds the survey start's heading and distance from side 0's wall. Distances in metres,
    angles in radians.
    """

    scale_range: tuple[float, float] = Field(
        (0.7, 1.4),
        description="a side's metres per odometry metre outside this is not used (nor a "
        "survey's metric_scale)",
    )
    turn_scale_range: tuple[float, float] = Field(
        (0.8, 1.25), description="an odometry turn per true turn outside this is not used"
    )
    min_corner_fraction: float = Field(
        0.5,
        ge=0,
        le=1,
        description="least share of the sides whose corner a wall or front line must place; "
        "fewer: the odometry poses are kept",
    )
    front_agree_m: float = Field(
        0.12,
        gt=0,
        description="a front line within this of the walk between the corners also anchors "
        "its side (m)",
    )
    level_m: float = Field(
        0.05,
        gt=0,
        description="the survey's last side: front lines of the lap before that read this "
        "close to each other (m) saw one thing standing before the wall",
    )
    level_lines: int = Field(2, ge=1, description="... and at least this many of them saw it")
    face_min_m: float = Field(
        0.08,
        ge=0,
        description="a side line this much or more before its wall saw a piece of furniture "
        "whose front the map keeps (m)",
    )
    face_frames: int = Field(
        3, ge=1, description="... when at least this many consecutive frames saw it"
    )
    face_margin_m: float = Field(
        0.15, ge=0, description="... widened by this beyond the first and last frame's foot (m)"
    )
    front_heading_m: float = Field(
        4.0,
        gt=0,
        description="a farther wall's line within this gives the start's heading (its angle, "
        "not its distance; m)",
    )
    line_std_m: float = Field(
        0.03,
        gt=0,
        description="a floor line's distance, one sigma (m; NAO's lens reads 2-4 cm long)",
    )
    line_std_rad: float = Field(0.01, gt=0, description="a floor line's angle, one sigma (rad)")
    min_angle_gate_rad: float = Field(
        0.12,
        ge=0,
        description="a side line's angle this close to the prediction is always used (rad)",
    )
    edge_m: float = Field(
        0.15,
        gt=0,
        description="a side line that jumps more than this between frames sees another thing "
        "(m); less than a doorway's recess: at 0.2 m the paper room's doorway was entered but "
        "its end missed and a whole side read 0.18 m off; over 30 surveys 0.15 m made no map "
        "pose worse (paper room 0.077 -> 0.047 m); lines err 1-4 cm, a step's sideways "
        "odometry 1-2 cm",
    )
    start_heading_m: float = Field(
        1.0,
        ge=0,
        description="the survey start's heading to its wall is its own line's, unless side "
        "0's frames within this walk (m), each turned back by the odometry's turn since the "
        "start, agree on another: one line seen past furniture once turned a map 0.2 rad; "
        "the frames carry the odometry's turn error, so the start's own line is preferred",
    )
    start_view_std_rad: float = Field(
        0.05,
        gt=0,
        description="an unclean start view's heading (scattered, or a far wall's), one sigma "
        "(rad), at least the views' own spread; weighed against side 0's frames': over 125 "
        "surveys such views erred 1.7 deg at the median, 12 deg at p90 (clean ones 0.14 and "
        "0.48 deg)",
    )
    start_frames_std_rad: float = Field(
        0.014,
        gt=0,
        description="side 0's frames' heading to the wall less the odometry's turn since the "
        "start, one sigma (rad): over 125 surveys it erred 0.78 deg (std; 0.40 deg median "
        "of abs)",
    )
    start_clean_std_rad: float = Field(
        0.005,
        gt=0,
        description="a clean start view's heading (the side wall seen whole and straight), "
        "one sigma (rad): over 125 surveys such views erred 0.14 deg at the median, 0.48 "
        "deg at p90; a door beside the start (its face 1.8 cm proud of the skirting) turned "
        "four views 1 deg. The map records its frame's heading sigma (heading_std_rad)",
    )
    clean_rms_m: float = Field(
        0.006,
        gt=0,
        description="a start view's line scattered more than this (RMS, m) does not give its "
        "heading",
    )
    clean_fraction: float = Field(
        0.4,
        ge=0,
        le=1,
        description="nor one with less of its boundary on it: a view centred on the wall's "
        "foot also shows the wall behind or furniture (0.45-0.6 on the line; 0.6 left one "
        "start one view, 1.2 deg off); over 52 surveys the start heading's p90 error "
        "0.76 -> 0.63 deg with 0.4",
    )
    start_from_wall_frames: int = Field(
        8,
        ge=1,
        description="a survey start beside furniture: its distance from the wall is carried "
        "back by the odometry's walk from side 0's frames that see the wall within this many "
        "frames (their median), not its stretch's depth (two chests read as one put a start "
        "9.7 cm off; the walk back errs 1-5 cm)",
    )
    start_agree_m: float = Field(
        0.04,
        ge=0,
        description="the start's own line places it unless those frames, carried back, "
        "disagree by more than this (m): in a corner one view can read the wall behind",
    )
    start_views: int = Field(
        3,
        ge=1,
        description="... unless at least this many of the start's views repeat its line: "
        "views from the standing robot measure where it stands, the frames carried back add "
        "the odometry's sideways walk (0.01-0.06 m per 0.2 m step: 8 of 18 origins "
        "0.05-0.11 m off); one view, or two that disagree, is a corner's or the arm's "
        "misreading as often",
    )
    start_views_m: float = Field(0.015, ge=0, description="... within this of the start's line (m)")
    end_frames: int = Field(
        3,
        ge=1,
        description="a side's last frames whose wall lines place where it ended (a corner's "
        "plant or sideboard is often all the last frame sees)",
    )
    wall_level_m: float = Field(
        0.1,
        gt=0,
        description="stretches of a side's lines whose levels are this close see the same "
        "thing (m)",
    )
    wall_again_m: float = Field(
        0.05,
        ge=0,
        description="a nearer or farther level of min_wall_frames lines or more, never "
        "bordering the wall's, whose lines read within this of the wall's (medians, m) is the "
        "wall seen again: levels chained through runs of fronts err (map origins 0.136 and "
        "0.106 m off); the survey keeps the wall at its offset to 1-3 cm, a front stands "
        "nearer by its depth",
    )
    min_wall_frames: int = Field(3, ge=1, description="least frames that must see a side's wall")
    wall_support: float = Field(
        0.2,
        ge=0,
        le=1,
        description="and the least share of the side's lines that must (the wall is the "
        "farthest level so seen)",
    )
    hidden_early_m: float = Field(
        0.7,
        gt=0,
        description="a side's lines ahead within this walk of its start (m) say how far "
        "ahead what it walked towards stood: a NAO's odometry errs 5-10 %, 3-7 cm so far "
        "(at 1 m, one wall of 87 surveys read 0.15 m nearer than it was)",
    )
    hidden_min_m: float = Field(
        0.15,
        ge=0,
        description="... this much or more nearer than the room's wall, with the next side's "
        "lines on one level, is a front hiding that wall all along (m)",
    )
    hidden_max_m: float = Field(
        1.0, gt=0, description="... up to this deep (m; a wardrobe 0.6, a sofa 0.9)"
    )

    @field_validator("scale_range", "turn_scale_range")
    @classmethod
    def _range_ok(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not 0 < v[0] <= v[1]:
            raise ValueError("must be [low, high] with 0 < low <= high")
        return v


class MapTuning(_Model):
    """Tuning of map building (landmarks, pose graph, bundle adjustment, checks, wall poses)."""

    landmarks: LandmarkTuning = LandmarkTuning()
    pose_graph: PoseGraphTuning = PoseGraphTuning()
    bundle: BundleTuning = BundleTuning()
    checks: MapCheckTuning = MapCheckTuning()
    wall_poses: WallPoseTuning = WallPoseTuning()


class MapConfig(_Model):
    """Algorithm 4: features -> bag of words -> Growing Cell Structures."""

    features: Literal["akaze", "orb", "sift"] = Field("akaze", description="local features")
    neurons: int = Field(300, ge=3, le=5000, description="GCS target size")
    epochs: int = Field(300, ge=1, le=10000, description="passes over the training images")
    seed: int = Field(0, ge=0, description="seed of vocabulary and GCS")
    vocabulary_size: int = Field(256, ge=8, le=4096, description="visual words")
    tuning: MapTuning = Field(
        MapTuning(), description="landmark, pose-graph, bundle, check and wall-pose tuning"
    )
    akaze_threshold: float = Field(
        0.001, gt=0, le=0.1, description="A-KAZE detector threshold (lower finds more keypoints)"
    )
    min_keypoints: int = Field(
        100,
        ge=0,
        le=5000,
        description="A-KAZE: an image with fewer keypoints keeps those above the threshold / "
        "sqrt(10), / 10, ... down to 3e-5 (one pass at the lowest; 0 = a fixed threshold)",
    )
    apply_metric_scale: bool = Field(
        False,
        description="scale the keyframe poses by the survey's floor-line metric_scale (for "
        "surveys that keep their odometry poses); off by default: the wall poses fix the "
        "scale, and the floor-line scale read 2-4 % off in unseen rooms (docs/history/RESULTS.md)",
    )
    wall_poses: bool = Field(
        True,
        description="take the keyframe poses from the survey's walls (the known circuit, the "
        "side walls' floor lines, the farthest a side agrees with, where each side ended, "
        "odometry only for the distance along a side) instead of the odometry; surveys "
        "without floor-line records keep their odometry",
    )
    far_pictures: bool = Field(
        True,
        description="add the survey's far pictures (survey.far_yaws_rad) to the map's "
        "keyframes for the verified localizer (features, landmarks, retrieval); the paper's "
        "vocabulary, GCS and neuron poses use the wall pictures either way",
    )


class LocalizeMode(enum.StrEnum):
    """How a pose is estimated from query images (a ``str``: ``"paper"`` == PAPER)."""

    VERIFIED = "verified"  # retrieval + landmark PnP + joint refinement
    PAPER = "paper"  # Algorithm 5: the GCS winners' mean pose


class LocalizeStrategy(enum.StrEnum):
    """How the localize behaviour takes its query pictures."""

    SCAN = "scan"  # a head sweep (and quarter turns in place while unsure)
    PAPER = "paper"  # the paper's 1-2 pictures towards the nearest wall


class FilterTuning(_Model):
    """The localization filter's sensor and motion models and decisions (naoloc.localization).

    Every figure the filter uses is here; ``localize.filter`` in a config overrides any.
    Likelihoods are in nats (natural log); a decision compares evidence, not ad-hoc scores.
    """

    face_reach_m: float = Field(
        0.3,
        ge=0,
        description="a furniture front the survey saw explains a floor line whose foot lies "
        "this near the stretch of it seen (m)",
    )
    candidates: int = Field(5, ge=1, le=50, description="keyframes retrieved per picture")
    window: int = Field(
        40, ge=2, le=1000, description="observations a new hypothesis is replayed through"
    )
    near_m: float = Field(
        0.05,
        ge=0,
        description="an earlier observation taken this near (m, by the odometry) also corrects a "
        "new hypothesis; farther ones only score it",
    )
    near_rad: float = Field(0.05, ge=0, description="the same in heading (rad)")
    pool_m: float = Field(
        0.3,
        ge=0,
        description="pictures taken within this of here (m) pool their matches for a planar "
        "RANSAC proposal",
    )
    pool_bearing_rad: float = Field(
        0.015, gt=0, description="the pooled RANSAC's bearing tolerance (rad)"
    )
    pool_samples: int = Field(
        1500, ge=0, le=100000, description="match pairs the pooled RANSAC draws"
    )
    pool_keep: int = Field(3, ge=0, le=50, description="poses the pooled RANSAC proposes at most")
    shift_from: int = Field(
        3,
        ge=0,
        le=50,
        description="hypotheses that get siblings moved to explain an unexplained floor line",
    )
    shift_min_m: float = Field(0.05, ge=0, description="smallest move of such a sibling (m)")
    shift_max_m: float = Field(1.0, ge=0, description="largest move of such a sibling (m)")
    shift_explained_nats: float = Field(
        2.0,
        ge=0,
        description="a line giving a hypothesis more evidence than this is explained (nats)",
    )
    line_proposals: int = Field(
        8, ge=0, le=100, description="poses the floor lines propose at most (the pictures' best)"
    )
    near_proposal_m: float = Field(
        1.0, ge=0, description="line poses beside a picture's proposal come from within this (m)"
    )
    near_proposal_rad: float = Field(0.3, ge=0, description="... and this (rad)")
    explore_from: int = Field(
        1, ge=0, le=50, description="hypotheses whose neighbours along the walls' axes are tried"
    )
    explore_margin_nats: float = Field(
        3.0, ge=0, description="a neighbour must gain this much of the pictures' evidence (nats)"
    )
    quick_pictures: int = Field(
        8, ge=1, le=1000, description="latest pictures a proposal's quick score looks at"
    )
    informative_features: int = Field(
        40,
        ge=0,
        description="a picture with fewer features says too little to prefer another place "
        "to the leading one, or to judge a place unless the map expects its landmarks in view",
    )
    expected_landmarks: int = Field(
        300,
        ge=0,
        description="landmarks the map must put in a picture's view from a place (within "
        "expect_range_m) for the picture to judge that place even without a match (0: off)",
    )
    expect_range_m: float = Field(
        4.0, gt=0, description="farthest landmark a picture is expected to show (m)"
    )
    line_evidence_cap_nats: float = Field(
        4.0,
        gt=0,
        description="most evidence one floor picture's lines give (nats): they share the walls' "
        "errors",
    )
    picture_evidence_cap_nats: float = Field(
        40.0,
        gt=0,
        description="most evidence one picture gives (nats): its features share the map's errors",
    )
    explore_steps_m: tuple[float, ...] = Field(
        (-0.6, -0.45, -0.3, -0.2, -0.1, 0.1, 0.2, 0.3, 0.45, 0.6),
        description="steps along the walls' axes an explored neighbour is moved by (m)",
    )
    proposal_sigma: tuple[float, float] = Field(
        (0.3, 0.2),
        description="a new hypothesis' uncertainty before its picture corrects it (m, rad)",
    )
    line_proposal_sigma: tuple[float, float] = Field(
        (0.06, 0.04), description="a line pose's uncertainty (m, rad)"
    )
    neighbours: int = Field(
        3, ge=1, le=10, description="nearest landmark descriptors a feature may be (any of)"
    )
    distinct_ratio: float = Field(
        0.8,
        gt=0,
        le=1,
        description="Lowe's ratio over the whole map for a feature's match to weigh whether "
        "this is the mapped room",
    )
    identity_object_m: float = Field(
        1.0,
        gt=0,
        description="distinctive matches within this of landmarks that already spoke for the "
        "room at a place are one object's (m; a picture on the wall): one object gives a "
        "place at most identity_cap_nats that this is the mapped room, however often it is "
        "seen (its twin may hang in another room: rooms share prints)",
    )
    identity_forget_per_picture: float = Field(
        0.01,
        ge=0,
        lt=1,
        description="share of the evidence that this is the mapped room a hypothesis forgets "
        "per picture with distinctive matches (slower than forget_per_observation: the room "
        "does not change; a blank or blurred view ages nothing)",
    )
    identity_cap_nats: float = Field(
        12.0,
        gt=0,
        description="most evidence one picture gives that this is the mapped room (nats): "
        "below null_nats, so no single picture decides it",
    )
    identity_floor_nats: float = Field(
        3.0,
        gt=0,
        description="most evidence one picture or one scan's floor lines give against the "
        "mapped room (nats): they share one view (a repeated texture, a poster matched to its "
        "twin, a skirting read as the floor's edge), so one view alone cannot undo what many "
        "showed",
    )
    min_pnp_inliers: int = Field(
        12, ge=6, description="PnP inliers of one picture that propose a new hypothesis"
    )
    pnp_reprojection_px: float = Field(4.0, gt=0, description="PnP RANSAC inlier threshold (px)")
    pnp_iterations: int = Field(100, ge=1, le=10000, description="PnP RANSAC iterations")
    camera_height_tolerance_m: float = Field(
        0.3, gt=0, description="largest difference of a PnP camera from the head's height (m)"
    )
    pixel_sigma_px: float = Field(
        3.0, gt=0, description="reprojection noise of a landmark at its pose (px, std)"
    )
    match_outlier_share: float = Field(
        0.5, gt=0, lt=1, description="prior share of a picture's landmark matches that are wrong"
    )
    match_weight: float = Field(
        0.2,
        gt=0,
        le=1,
        description="evidence one landmark match carries (matches of a picture share the "
        "map's errors: they are not independent)",
    )
    min_inliers: int = Field(
        8, ge=3, description="landmarks a picture must fit to update a hypothesis"
    )
    landmark_sigma_m: float = Field(
        0.05,
        ge=0,
        description="error of the map's landmarks in one place (m, std): a picture's pose "
        "is no better (PnP poses erred a median 0.07 m in six rooms)",
    )
    landmark_sigma_rad: float = Field(
        0.005, ge=0, description="heading error of a picture's pose from the landmarks (rad)"
    )
    wall_sigma_m: float = Field(
        0.015,
        ge=0,
        description="error of the map's walls (m, std; the survey places them to 1-4 cm)",
    )
    wall_sigma_rad: float = Field(
        0.01, ge=0, description="direction error of the map's walls (rad, std)"
    )
    map_floor_m: float = Field(
        0.02,
        ge=0,
        description="error no number of observations removes: the map's own placement of "
        "its walls and landmarks around the robot (m, std; added to the reported "
        "covariance); a map whose survey's laps show a larger error (meta keyframe_sigma_m) "
        "uses that",
    )
    map_floor_rad: float = Field(0.01, ge=0, description="the same for the heading (rad, std)")
    map_frame_rad: float = Field(
        0.005,
        ge=0,
        description="the map frame's heading error (rad, std) for a map that does not record "
        "its own (meta wall_poses.heading_std_rad): the survey start's heading to its wall "
        "turns the whole map about its origin, so a pose r m from it is off by r times it, "
        "across; added to the reported covariance",
    )
    line_sigma_m: float = Field(
        0.01,
        gt=0,
        description="floor-line distance noise (m, std). Measured: lines of a wall at rest "
        "read 0.012-0.015 m (robust std) off the map's wall up to 2 m, 0.02 m at 2-3 m, "
        "0.028 m beyond (8073 lines of 860 localizations in 43 rooms, tools/line_noise.py)",
    )
    line_sigma_per_m: float = Field(
        0.005, ge=0, description="floor-line distance noise growing with distance (m per m)"
    )
    line_sigma_rad: float = Field(
        0.015,
        gt=0,
        description="floor-line direction noise (rad; measured 0.009-0.016 up to 3 m, 0.026 "
        "beyond)",
    )
    walk_line_sigma_m: float = Field(
        0.02,
        gt=0,
        description="floor-line distance noise while the robot walks (m, std): the camera "
        "sways with the gait; not measured (the at-rest model before stop 52)",
    )
    walk_line_sigma_per_m: float = Field(
        0.02, ge=0, description="the same, growing with distance (m per m)"
    )
    walk_line_sigma_rad: float = Field(
        0.04, gt=0, description="floor-line direction noise while the robot walks (rad)"
    )
    walking_step_m: float = Field(
        0.001,
        ge=0,
        description="a scan whose odometry moved more than this since the previous "
        "observation was taken walking (m; a standing NAO's odometry does not move)",
    )
    line_outlier_share: float = Field(
        0.4, gt=0, lt=1, description="prior share of floor lines that are not a wall's foot"
    )
    min_line_span_m: float = Field(
        0.25, ge=0, description="floor lines shorter than this along the floor are not used (m)"
    )
    line_agree_rad: float = Field(
        0.1, gt=0, description="lines that propose poses agree on the heading within this (rad)"
    )
    line_agree_m: float = Field(0.12, gt=0, description="their coordinates are one within this (m)")
    behind_wall_m: float = Field(
        0.2, ge=0, description="a proposed pose puts no seen line farther behind its wall (m)"
    )
    line_beyond_share: float = Field(
        0.02,
        gt=0,
        le=1,
        description="share of floor lines seen beyond the map's walls (past the skirting's "
        "band, line_ghost_share) from the true pose: the likelihood of a line no wall nor "
        "furniture of the mapped room makes (1 % of 9818 recorded lines, RESULTS stop 53)",
    )
    line_ghost_share: float = Field(
        0.15,
        ge=0,
        description="a line this share of its range beyond the map's walls is still the mapped "
        "room's: a skirting board's top edge read as the floor's boundary stands 10-27 % "
        "farther than the wall's foot (camera.floor_lines.ghost_ratio)",
    )
    clutter_aligned: float = Field(
        0.8,
        ge=0,
        le=1,
        description="share of non-wall floor lines along a wall's direction (furniture "
        "stands along the walls)",
    )
    clutter_aligned_rad: float = Field(
        0.1, gt=0, le=0.78, description="how near a wall's direction such a line is (rad)"
    )
    line_range_m: float = Field(
        3.0, gt=0, description="farthest floor line the detector reports (m): the clutter range"
    )
    trans_per_m: float = Field(0.12, ge=0, description="odometry distance noise per metre")
    rot_per_rad: float = Field(0.2, ge=0, description="odometry turn noise per radian")
    rot_per_m: float = Field(0.1, ge=0, description="odometry heading noise per metre (rad/m)")
    slip_per_sqrt_rad: float = Field(
        0.02,
        ge=0,
        description="odometry position noise per square root of the radians turned (m): a "
        "NAO's feet slip as it turns, in place too",
    )
    floor_m: float = Field(0.002, ge=0, description="odometry noise of any step (m)")
    floor_rad: float = Field(0.002, ge=0, description="odometry noise of any step (rad)")
    max_hypotheses: int = Field(12, ge=1, le=100, description="hypotheses kept at most")
    prune_nats: float = Field(
        25.0, gt=0, description="a hypothesis this far below the best one is dropped (nats)"
    )
    merge_mahalanobis: float = Field(
        3.0, gt=0, description="hypotheses closer than this (Mahalanobis) are merged"
    )
    gate_mahalanobis: float = Field(
        4.0,
        gt=0,
        description="a picture's pose farther than this from a hypothesis does not "
        "update it (Mahalanobis, 3 degrees of freedom)",
    )
    forget_per_observation: float = Field(
        0.03,
        ge=0,
        lt=1,
        description="share of its evidence a hypothesis forgets per observation (a carried "
        "robot's old place fades)",
    )
    fade_share: float = Field(
        0.15,
        gt=0,
        lt=1,
        description="the leading place's recent picture evidence below this share of its "
        "usual makes it contradicted (gives no pose): the robot was carried, or it is wrong",
    )
    recent_rate: float = Field(
        0.5,
        gt=0,
        le=1,
        description="weight of the latest informative picture in the recent "
        "average of a place's evidence",
    )
    usual_rate: float = Field(
        0.1,
        gt=0,
        le=1,
        description="weight of the latest informative picture in the usual "
        "(slow) average of a place's evidence",
    )
    usual_hold_share: float = Field(
        0.5,
        gt=0,
        le=1,
        description="the usual average stops following a place's evidence while the recent "
        "one is below this share of it (a fading place keeps what it used to explain)",
    )
    contradiction_nats: float = Field(
        6.0,
        gt=0,
        description="a picture another place explains this much better than the leading "
        "one (nats) counts against the leader; two in a row and it gives no pose",
    )
    null_nats: float = Field(
        20.0,
        gt=0,
        description="evidence a place must have over 'these observations are not of the "
        "mapped room' to be believed (nats; prior log-odds of the other room)",
    )
    confident: float = Field(
        0.9, gt=0, le=1, description="probability of the best place for a tracking pose"
    )
    max_sigma_m: float = Field(
        0.12, gt=0, description="a belief wider than this (position std, m) gives no pose"
    )
    max_sigma_rad: float = Field(
        0.1, gt=0, description="a belief wider than this (heading std, rad) gives no pose"
    )
    verdict_pictures: int = Field(
        5,
        ge=1,
        description="pictures with features before the filter says 'not the mapped room'",
    )


class LocalizeConfig(_Model):
    """Algorithm 5 and beyond."""

    mode: LocalizeMode = Field(
        LocalizeMode.VERIFIED,
        description="paper: GCS winners' mean pose; verified: RANSAC-checked retrieval",
    )
    images: int = Field(2, ge=1, le=8, description="images taken per estimate")
    resolution: int | None = Field(
        None,
        description="NAOqi resolution id of the query pictures (localize, go-home); null = "
        "camera.resolution (2 = kVGA: a far wall's features at the size the survey saw them "
        "from 1 m, at four times the extraction time)",
    )
    head_pitch_rad: float = Field(
        -0.672,
        ge=-0.672,
        le=0.515,
        description="head pitch of the query pictures (rad, negative looks up; clamped to "
        "the head's limits at each yaw)",
    )

    floor_lines: Literal["off", "unsure", "always"] = Field(
        "always",
        description="scan strategy: measure the floor-wall lines around the robot (bottom "
        "camera, 10 pictures) and with the map's walls: a PnP pose they confirm takes their "
        "pose; otherwise their pose the pictures' matches support clearly best (method "
        "floorlines). always (default), unsure (only when the pictures verified no "
        "confident pose) or off; YAML's bare false/off is off, true/on is always",
    )

    settle_sigma_m: float = Field(
        0.03,
        gt=0,
        description="scan strategy: stop looking once the tracked pose's position std, less "
        "the map's own error the filter adds to it (localize.filter.map_floor_m or the map's "
        "keyframe_sigma_m), is at most this (m); otherwise look until the sweep ends",
    )
    extra_turns: int = Field(
        3,
        ge=0,
        le=8,
        description="scan strategy: turns in place, each followed by a sweep, while the "
        "belief is not concentrated (0: never)",
    )
    extra_turn_rad: float = Field(
        math.pi / 2, gt=0, le=math.pi, description="... each this far (rad)"
    )
    filter: FilterTuning = Field(
        FilterTuning(), description="the localization filter's models and decisions"
    )

    @field_validator("resolution")
    @classmethod
    def _res_ok(cls, v: int | None) -> int | None:
        return None if v is None else _resolution_id(v)

    @field_validator("floor_lines", mode="before")
    @classmethod
    def _floor_lines_word(cls, v: object) -> object:
        # YAML reads a bare off/no/false as False and on/yes/true as True.
        if isinstance(v, bool):
            return "always" if v else "off"
        return v

    def camera(self, camera: CameraConfig) -> CameraConfig:
        """The camera settings of the query pictures: ``camera`` at ``resolution``."""
        if self.resolution is None:
            return camera
        return camera.model_copy(update={"resolution": self.resolution})


class GoHomeConfig(_Model):
    """Walk back to the map origin."""

    tolerance_m: float = Field(
        0.05, gt=0, description="stop when the belief is this close to the origin (m)"
    )
    max_tries: int = Field(
        8,
        ge=1,
        le=50,
        description="looks from standstill, the first one included (another when the "
        "belief is lost on the way)",
    )
    contacts: int = Field(
        2,
        ge=0,
        le=10,
        description="contacts while walking that it backs off from and plans around (the "
        "next one stops it: blocked)",
    )
    back_off_m: float = Field(
        0.2, gt=0, le=1.0, description="how far it steps back after a contact (m)"
    )
    step_away_m: float = Field(
        0.3,
        ge=0,
        le=1.0,
        description="after a look that found no pose it steps this far away from the walls "
        "that look saw near (m; 0: it looks again where it stands)",
    )
    near_wall_m: float = Field(
        1.0,
        gt=0,
        le=3.0,
        description="walls nearer than this push the step away (m)",
    )
    align_m: float = Field(
        1.0,
        ge=0,
        le=5.0,
        description="within this of home (along the path) it turns to home's heading while "
        "it walks, so it arrives facing map +x (m; 0: it turns there)",
    )
    replan_s: float = Field(
        3.0, gt=0, description="re-plan the path from the belief this often while walking (s)"
    )
    reached_m: float = Field(
        0.15, gt=0, description="a waypoint this near the belief's pose counts as passed (m)"
    )
    lost_frames: int = Field(
        15, ge=1, description="frames without a pose while walking before it stops to look"
    )
    approach_m: float = Field(
        0.3,
        gt=0,
        description="within this of home (by the belief) the walk ends and the final approach "
        "of short steps begins (m)",
    )
    final_steps: int = Field(3, ge=0, le=20, description="the final approach's steps, at most")
    contact_ahead_m: float = Field(
        0.25,
        ge=0,
        description="a contact while walking: the floor this far ahead of the belief's pose "
        "is marked blocked (m; the body's front edge) ...",
    )
    contact_radius_m: float = Field(
        0.15, gt=0, description="... in a disc this wide (m; the thing it touched)"
    )
    time_per_m_s: float = Field(
        30.0, gt=0, description="robot time allowed per metre of the first plan (s)"
    )
    min_time_s: float = Field(60.0, gt=0, description="... and at least this (s)")


class Config(_Model):
    """The whole naoloc configuration (docs/cli.md lists every key). Every key has a default."""

    robot: RobotConfig = RobotConfig()
    world: WorldConfig = WorldConfig()
    camera: CameraConfig = CameraConfig()
    survey: SurveyConfig = SurveyConfig()
    map: MapConfig = MapConfig()
    localize: LocalizeConfig = LocalizeConfig()
    go_home: GoHomeConfig = GoHomeConfig()

    def start_pose(self) -> tuple[float, float, float]:
        """The robot's start pose in the room frame (x, y m; theta rad)."""
        if self.world.start_pose is not None:
            return self.world.start_pose
        off = self.survey.wall_offset_m
        return (off, off, 0.0)

    def survey_sides(self) -> tuple[float, float]:
        """Sides ``(along x, along y)`` of the survey rectangle in metres."""
        if self.survey.side_m is not None:
            return self.survey.side_m
        sx, sy = self.world.room.size_m
        off = self.survey.wall_offset_m
        return (sx - 2 * off, sy - 2 * off)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict of the resolved config, without secrets (``robot.password``).

        Everything naoloc writes to disk (config copies, dataset and map metadata,
        evaluation outputs) comes from here, so a secret never reaches a file.
        """
        return self.model_dump(mode="json", exclude=_SECRETS)

    def to_yaml(self) -> str:
        """The resolved config as YAML text."""
        return yaml.safe_dump(self.to_dict(), sort_keys=False)

    def with_overrides(self, overrides: dict[str, Any]) -> Config:
        """A new config with a nested dict of keys replaced (validated again)."""
        return _validate(_deep_merge(self.model_dump(), overrides), "<overrides>")


# Keys never written anywhere (model_dump ``exclude`` form); see Config.to_dict.
_SECRETS: dict[str, Any] = {"robot": {"password"}}


def _deep_merge(base: dict[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _deep_merge(out[key], value)
        else:
            out[key] = value
    return out


def _format_error(source: str, err: ValidationError) -> str:
    errors = err.errors(include_url=False)
    first = errors[0]
    path = ".".join(str(p)[:60] for p in first.get("loc", ())) or "<root>"
    kind = first.get("type", "")
    if kind == "extra_forbidden":
        msg = "unknown key" + _did_you_mean(tuple(first.get("loc", ())))
    else:
        msg = " ".join(str(first.get("msg", "invalid value")).split())[:160]
        if "input" in first and kind != "missing" and "password" not in path:
            msg += f" (got {short_repr(first['input'])})"  # bounded: never a huge repr
    more = len(errors) - 1
    suffix = f" (+{more} more)" if more > 0 else ""
    return f"{source}: {path}: {msg}{suffix}"


def _model_in(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model inside ``annotation`` (``M``, ``M | None``, ``list[M]``), if any."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _did_you_mean(loc: tuple[Any, ...]) -> str:
    """``"; did you mean 'size_m'?"`` for an unknown key at ``loc``, or ``""``."""
    model: type[BaseModel] | None = Config
    for part in loc[:-1]:
        if model is None:
            return ""
        if isinstance(part, int):  # an item of a list: the model stays the item's
            continue
        field = model.model_fields.get(str(part))
        model = None if field is None else _model_in(field.annotation)
    if model is None or not loc:
        return ""
    close = difflib.get_close_matches(str(loc[-1]), list(model.model_fields), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


# Ranges of keys whose Field has none (path -> inclusive [low, high]), per list item.
_SANE_RANGES: dict[str, tuple[float, float]] = {
    "robot.move_timeout_s": (0.0, 86400.0),
    "world.odometry.heading_bias_rad_per_m": (-1.0, 1.0),
    "world.start_pose": (-100.0, 100.0),
    "survey.side_m": (0.0, 50.0),
    "survey.wall_offset_m": (0.0, 25.0),
    "survey.head_yaw_rad": (-2.0857, 2.0857),  # NAO HeadYaw limits (rad)
    "go_home.tolerance_m": (0.0, 10.0),
}


def _check_ranges(values: dict[str, Any], source: str) -> None:
    for key, (low, high) in _SANE_RANGES.items():
        value: Any = values
        for part in key.split("."):
            value = value.get(part) if isinstance(value, dict) else None
        items = value if isinstance(value, list | tuple) else [value]
        for item in items:
            if isinstance(item, int | float) and not low <= item <= high:
                raise ConfigError(f"{source}: {key}: {item} is outside [{low:g}, {high:g}]")


# Keys a release retired: dropped on load, with a warning, so that the configs saved with
# earlier datasets and recordings still load (their defaults take over). Dotted path ->
# what replaced it.
RETIRED_KEYS: dict[str, str] = {
    "map.tuning.wall_poses.start_gate_rad": "map.tuning.wall_poses.start_view_std_rad and "
    "start_frames_std_rad",
}


def _drop_retired(data: dict[str, Any], source: str) -> dict[str, Any]:
    """``data`` without :data:`RETIRED_KEYS` (copied along their paths, never in place)."""
    for dotted, instead in RETIRED_KEYS.items():
        path = dotted.split(".")
        node: Any = data
        for key in path[:-1]:
            node = node.get(key) if isinstance(node, dict) else None
        if isinstance(node, dict) and path[-1] in node:
            logging.getLogger(__name__).warning(
                "%s: %s is retired and ignored (replaced by %s)", source, dotted, instead
            )
            data = _without(data, path)
    return data


def _without(data: dict[str, Any], path: list[str]) -> dict[str, Any]:
    """A copy of ``data`` without the key at ``path`` (the dicts along it copied)."""
    key, *rest = path
    if not rest:
        return {k: v for k, v in data.items() if k != key}
    return {**data, key: _without(data[key], rest)}


def _validate(data: Any, source: str) -> Config:
    if data is None:
        data = {}
    if isinstance(data, dict):
        data = _drop_retired(data, source)
    check_values(data, source, model=Config)  # finite, bounded, no `step_m: true`, no 10**12
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: the top level must be a mapping, got {type(data).__name__}")
    try:
        cfg = Config.model_validate(data)
    except ValidationError as err:
        raise ConfigError(_format_error(source, err)) from None
    values = cfg.model_dump()
    check_values(values, source)  # strings such as "nan" that pydantic turned into floats
    _check_ranges(values, source)
    sides = cfg.survey_sides()
    if min(sides) <= 0:
        raise ConfigError(
            f"{source}: survey.wall_offset_m: {cfg.survey.wall_offset_m} m leaves no circuit "
            f"in a room of {list(cfg.world.room.size_m)} m"
        )
    x, y, theta = cfg.start_pose()
    if cfg.robot.backend != "naoqi":
        sx, sy = cfg.world.room.size_m
        if not (0 < x < sx and 0 < y < sy) or not math.isfinite(theta):
            raise ConfigError(f"{source}: world.start_pose: {[x, y, theta]} is outside the room")
    return cfg


def load_config(source: str | Path | dict[str, Any] | Config | None) -> Config:
    """Load and validate a config.

    Args:
        source: A YAML file path, a nested dict, a :class:`Config`, or None for defaults.

    Returns:
        The validated, immutable config.

    Raises:
        ConfigError: One line naming the file and key path of the first problem.
    """
    if isinstance(source, Config):
        return source
    if source is None:
        return _validate({}, "<defaults>")
    if isinstance(source, dict):
        return _validate(source, "<dict>")
    path = Path(source)
    if not path.exists() and is_config_name(str(source)):
        return load_shipped_config(str(source))
    data = load_yaml(read_text(path), str(path))
    return _validate(data, str(path))


# Named configs shipped in the package (``-c paper_room``): configs/*.yaml of the checkout,
# installed as naoloc/configs/*.yaml. The name is the file's stem without "sim_".


def _shipped_dir() -> Any:
    """The folder of shipped configs: inside the installed package, else the checkout's."""
    import importlib.resources

    installed = importlib.resources.files("naoloc").joinpath("configs")
    if installed.is_dir():
        return installed
    return Path(__file__).resolve().parent.parent / "configs"


def shipped_configs() -> dict[str, Any]:
    """Named configs shipped in the package: name -> file (a Traversable), sorted by name."""
    folder = _shipped_dir()
    if not folder.is_dir():
        return {}
    found = {}
    for entry in folder.iterdir():
        if entry.name.endswith(".yaml"):
            found[entry.name[: -len(".yaml")].removeprefix("sim_")] = entry
    return dict(sorted(found.items()))


def is_config_name(text: str) -> bool:
    """True when ``text`` looks like a config name, not a path (no folder, no extension)."""
    return bool(text) and "/" not in text and "\\" not in text and "." not in text


def load_shipped_config(name: str) -> Config:
    """Load a config shipped in the package by name (``paper_room``, ``lab_room``, ``nao``).

    Raises:
        ConfigError: One line listing the shipped names when ``name`` is none of them.
    """
    shipped = shipped_configs()
    entry = shipped.get(name.removeprefix("sim_"))
    if entry is None:
        names = ", ".join(shipped) or "none"
        raise ConfigError(f"{name}: no such config file or shipped config (shipped: {names})")
    source = f"{name} (configs/{entry.name})"
    data = load_yaml(entry.read_text(encoding="utf-8"), source)
    return _validate(data, source)
