"""Image formation of a simulated NAO camera, shared by the fake and the MuJoCo backends.

A renderer gives a clean pinhole RGB frame (principal point at the image centre, the field of
view of ``world.model``, widened by :func:`render_fov_for` when the lens distorts).
:class:`CameraModel` turns it into what a NAO's camera delivers, in the order light takes
through a camera:

1. lens: NAO's calibrated top camera (:data:`naoloc.robot.lens.NAO_LENS`: at VGA fx 557 px,
   principal point (309, 231), radial k1 -0.055; scaled to the resolution) and, optionally,
   a rolling shutter (rows exposed one after another, 0.9 frame times from first to last
   row);
2. motion blur: the image motion of the camera during the exposure time, from the camera's
   angular and linear velocity (optical frame) at the time of the frame;
3. exposure: auto exposure (AE) drives exposure time and then analog gain so that the mean
   luma approaches ``ae_target``; it runs at the subscription's frame rate and converges
   geometrically (half the log error per frame), so after a light change the frames
   adapt over a few frames, and a dim room gets brighter, noisier frames, not black ones;
4. vignetting (brightness falls toward the corners) and gray-world auto white balance;
5. sensor noise: shot noise of a 5000 electron full well (SNR 37 dB at saturation, the
   MT9M114's figure) plus read noise, both scaled by the analog gain, so high gain means
   more noise; luma noise per pixel, chroma noise per pixel pair;
6. YUV422: chroma averaged over horizontal pixel pairs (the NAO's native format).

The rendered frame stands for the scene exposed for 1/30 s at unity gain. Noise samples
come from a seeded bank of Gaussian samples read at a random offset per frame (drawing
fresh samples every frame would cost more than the rest of the model together).

What is not modelled: roll blur, depth-dependent blur (translation blur assumes the scene
is 1.5 m away), the Bayer pattern and its demosaicing, hot pixels, flicker.

This module depends on numpy and OpenCV only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from naoloc.config import CameraRealismConfig
from naoloc.robot.lens import NAO_LENS, render_fov

FULL_WELL_E = 5000.0  # electrons at 255: SNR = sqrt(5000) = 37 dB at saturation
READ_NOISE_E = 6.0  # electrons
CHROMA_NOISE = 0.7  # chroma noise std relative to luma noise std
NOMINAL_EXPOSURE_S = 1.0 / 30.0  # the exposure a rendered frame stands for (unity gain)
MIN_EXPOSURE_S = 1e-4
MAX_GAIN = 8.0  # analog gain limit (18 dB)
AE_RATE = 0.5  # fraction of the log brightness error corrected per camera frame
AE_SETTLED_FRAMES = 30  # a camera seen for the first time has run this long already
VIGNETTING = 0.3  # brightness loss in the image corners (nao profile)
AWB_LIMITS = (0.6, 1.8)  # gray-world channel gains
ROLLING_SHUTTER_FRAMES = 0.9  # first to last row, in frame times
BLUR_DEPTH_M = 1.5  # scene depth assumed for the blur of a translating camera
_BANK_MARGIN = 48  # px of noise bank beyond the frame, for random offsets
_LUMA = np.array([0.299, 0.587, 0.114], np.float32)


@dataclass(frozen=True)
class CameraSettings:
    """A camera-realism config with every ``null`` resolved from its profile.

    Attributes:
        sensor_noise: Shot and read noise of the sensor model.
        noise_std: Explicit Gaussian noise std (0-255 units), replaces the sensor model.
        blur_px: Extra Gaussian blur sigma in pixels (0 = none).
        exposure: Fixed brightness gain, or None for auto exposure.
        auto_white_balance: Gray-world white balance.
        vignetting: Brightness loss in the corners (0 = none).
        yuv422: Chroma averaged over horizontal pixel pairs.
        distortion: NAO's lens calibration.
        motion_blur: Blur along the camera's motion during the exposure.
        rolling_shutter: Rows exposed one after another.
        jpeg_quality: JPEG round trip quality, or None.
        ae_target: Auto exposure's target mean luma (0-255).
    """

    sensor_noise: bool
    noise_std: float
    blur_px: float
    exposure: float | None
    auto_white_balance: bool
    vignetting: float
    yuv422: bool
    distortion: bool
    motion_blur: bool
    rolling_shutter: bool
    jpeg_quality: int | None
    ae_target: float

    @property
    def identity(self) -> bool:
        """True when the model leaves frames exactly as rendered."""
        return not (
            self.sensor_noise
            or self.noise_std > 0
            or self.blur_px > 0
            or self.exposure is None
            or self.exposure != 1.0
            or self.auto_white_balance
            or self.vignetting > 0
            or self.yuv422
            or self.distortion
            or self.motion_blur
            or self.rolling_shutter
            or self.jpeg_quality is not None
        )


def resolve(cfg: CameraRealismConfig) -> CameraSettings:
    """Resolve a ``world.camera_realism`` block against its profile."""
    nao = cfg.profile == "nao"
    pick = cfg.pick
    exposure: float | None
    exposure = float(cfg.exposure) if cfg.exposure is not None else None if nao else 1.0
    return CameraSettings(
        sensor_noise=nao and cfg.noise_std is None,
        noise_std=float(cfg.noise_std or 0.0),
        blur_px=float(cfg.blur_px or 0.0),
        exposure=exposure,
        auto_white_balance=pick(cfg.auto_white_balance),
        vignetting=float(cfg.vignetting if cfg.vignetting is not None else (VIGNETTING * nao)),
        yuv422=pick(cfg.yuv422),
        distortion=cfg.lens_distortion,
        motion_blur=pick(cfg.motion_blur),
        rolling_shutter=bool(cfg.rolling_shutter),
        jpeg_quality=cfg.jpeg_quality,
        ae_target=float(cfg.ae_target),
    )


@dataclass(frozen=True)
class Motion:
    """The camera's velocity at the time of a frame, in its optical frame (x right, y down,
    z forward).

    Attributes:
        omega: Angular velocity (rad/s).
        velocity: Linear velocity (m/s).
    """

    omega: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass
class _Geometry:
    map_x: np.ndarray
    map_y: np.ndarray
    fixed: tuple[np.ndarray, np.ndarray]  # the maps in OpenCV's fixed-point form (faster)
    vignette: np.ndarray  # (h, w, 3) float32
    vignette_small: np.ndarray  # (30, 40) float32: what the AE's meter sees
    focal: float  # px of the output image
    noise_y: np.ndarray  # standard normal bank (h + m, w + m)
    noise_c: tuple[np.ndarray, np.ndarray]  # U and V banks, (h + m, w + m) each


def _lens_maps(
    width: int, height: int, hfov: float, vfov: float, distortion: bool
) -> tuple[np.ndarray, np.ndarray, float]:
    """Where each output pixel samples the rendered pinhole frame, and the output focal.

    With ``distortion`` the output images through :data:`naoloc.robot.lens.NAO_LENS` exactly
    (focal, principal point, k1), so naoloc's own undistortion inverts it; the render must
    cover the lens's view (:func:`naoloc.robot.lens.render_fov`), else its edge pixels repeat.
    """
    fr_x = (width / 2.0) / math.tan(hfov / 2.0)
    fr_y = (height / 2.0) / math.tan(vfov / 2.0)
    u, v = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
    if not distortion:
        return u.astype(np.float32), v.astype(np.float32), 0.5 * (fr_x + fr_y)
    xu, yu = NAO_LENS.normalized(u, v, width, height)
    mx = fr_x * xu + width / 2.0 - 0.5
    my = fr_y * yu + height / 2.0 - 0.5
    fx, fy, _, _ = NAO_LENS.at(width, height)
    return mx.astype(np.float32), my.astype(np.float32), 0.5 * (fx + fy)


def render_fov_for(fov: tuple[float, float], cfg: CameraRealismConfig) -> tuple[float, float]:
    """The field of view (rad) a simulator renders at for a camera of nominal ``fov``: wider
    than nominal when the camera images through NAO's lens (so the lens's view fits)."""
    if not resolve(cfg).distortion:
        return fov
    wide = render_fov(NAO_LENS)
    return (max(fov[0], wide[0]), max(fov[1], wide[1]))


def motion_blur(img: np.ndarray, du: float, dv: float) -> np.ndarray:
    """Smear an image along the segment ``(du, dv)`` pixels long (a moving camera's blur).

    A box blur of the segment's length along its direction: directly when the motion is
    within 10 degrees of horizontal or vertical (a panning or tilting head), else on the
    image rotated so that the motion is horizontal, and rotated back.
    """
    length = math.hypot(du, dv)
    n = max(1, round(length))
    if n < 2:
        return img
    ang = math.atan2(dv, du)
    if abs(math.sin(ang)) < 0.17:
        return cv2.blur(img, (n, 1), borderType=cv2.BORDER_REPLICATE)
    if abs(math.cos(ang)) < 0.17:
        return cv2.blur(img, (1, n), borderType=cv2.BORDER_REPLICATE)
    h, w = img.shape[:2]
    rot = cv2.getRotationMatrix2D((w / 2 - 0.5, h / 2 - 0.5), math.degrees(ang), 1.0)
    flat = cv2.warpAffine(img, rot, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    flat = cv2.blur(flat, (n, 1), borderType=cv2.BORDER_REFLECT)
    back = cv2.invertAffineTransform(rot)
    return cv2.warpAffine(flat, back, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


class CameraModel:
    """One simulated camera: its lens, its sensor and the state of its AE and AWB.

    Create one per camera (index) of a robot; frames of every subscription to that camera
    go through it, as they go through one sensor on a NAO.

    Args:
        cfg: ``world.camera_realism``.
        seed: The simulator's seed (mixed with ``cfg.seed`` and ``camera``).
        camera: Camera index (0 top, 1 bottom).
    """

    def __init__(self, cfg: CameraRealismConfig, seed: int, camera: int) -> None:
        self.settings = resolve(cfg)
        self._rng = np.random.default_rng([seed, cfg.seed, camera, 0xCA4])
        self._geometry: dict[tuple[int, int, float, float], _Geometry] = {}
        self._log_exposure: float | None = None  # log of exposure x gain, 1 = rendered frame
        self._log_awb = np.zeros(3)
        self._last_time: float | None = None
        self.exposure_s = NOMINAL_EXPOSURE_S  # of the last frame
        self.gain = 1.0  # analog gain of the last frame

    # ------------------------------------------------------------------ state
    def _frames_since(self, time_s: float, fps: float) -> int:
        if self._last_time is None or self._log_exposure is None:
            return AE_SETTLED_FRAMES
        frames = (time_s - self._last_time) * fps
        return int(min(AE_SETTLED_FRAMES, max(1, math.floor(frames + 1e-9))))

    def _update_exposure(self, luma_small: np.ndarray, frames: int, fps: float) -> float:
        """Run the AE for the camera frames since the last request; the exposure of this one.

        The frames in between saw the current scene; this frame is exposed with what the
        AE concluded from the frame before it, and its own meter reading is applied after.
        """
        s = self.settings
        t_max = 1.0 / max(float(fps), 15.0)
        if s.exposure is not None:
            log_e = math.log(s.exposure)
            applied = log_e
        else:
            lo = math.log(MIN_EXPOSURE_S / NOMINAL_EXPOSURE_S)
            hi = math.log(t_max / NOMINAL_EXPOSURE_S * MAX_GAIN)
            log_e = self._log_exposure if self._log_exposure is not None else 0.0
            target = math.log(s.ae_target)
            applied = log_e
            for k in range(frames):
                applied = log_e
                mean = float(np.minimum(luma_small * math.exp(log_e), 255.0).mean())
                log_e += AE_RATE * (target - math.log(max(mean, 0.5)))
                log_e = min(hi, max(lo, log_e))
                if k == frames - 2:
                    applied = log_e
        self._log_exposure = log_e
        total = math.exp(applied)
        self.exposure_s = min(t_max, max(MIN_EXPOSURE_S, total * NOMINAL_EXPOSURE_S))
        self.gain = max(1.0, total * NOMINAL_EXPOSURE_S / self.exposure_s)
        return total

    def _update_white_balance(self, small: np.ndarray, frames: int) -> np.ndarray:
        """Gray-world AWB, adapting at the AE's rate; the gains of this frame (G = 1)."""
        if not self.settings.auto_white_balance:
            return np.ones(3, np.float32)
        pixels = small.reshape(-1, 3)
        ok = pixels.max(axis=1) < 250  # clipped pixels carry no colour
        means = pixels[ok].mean(axis=0) if np.count_nonzero(ok) > 10 else pixels.mean(axis=0)
        means = np.maximum(means, 1.0)
        goal = np.log(np.clip(means[1] / means, *AWB_LIMITS))
        applied = goal + (self._log_awb - goal) * (1.0 - AE_RATE) ** (frames - 1)
        self._log_awb = goal + (self._log_awb - goal) * (1.0 - AE_RATE) ** frames
        return np.exp(applied).astype(np.float32)

    def _geometry_for(self, width: int, height: int, hfov: float, vfov: float) -> _Geometry:
        key = (width, height, hfov, vfov)
        geo = self._geometry.get(key)
        if geo is None:
            map_x, map_y, focal = _lens_maps(width, height, hfov, vfov, self.settings.distortion)
            yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
            r2: np.ndarray = ((xx - (width - 1) / 2) ** 2 + (yy - (height - 1) / 2) ** 2) / (
                ((width - 1) / 2) ** 2 + ((height - 1) / 2) ** 2
            )
            vignette = np.repeat(
                (1.0 - self.settings.vignetting * r2)[..., None], 3, axis=2
            ).astype(np.float32)
            m = _BANK_MARGIN
            noise_y = self._rng.standard_normal((height + m, width + m), dtype=np.float32)
            noise_c = (
                self._rng.standard_normal((height + m, width + m), dtype=np.float32),
                self._rng.standard_normal((height + m, width + m), dtype=np.float32),
            )
            small = cv2.resize(vignette[..., 0], (40, 30), interpolation=cv2.INTER_AREA)
            fixed = cv2.convertMaps(map_x, map_y, cv2.CV_16SC2)
            geo = _Geometry(map_x, map_y, fixed, vignette, small, focal, noise_y, noise_c)
            self._geometry[key] = geo
        return geo

    # ------------------------------------------------------------------ frames
    def process(
        self,
        rgb: np.ndarray,
        *,
        time_s: float,
        fps: float,
        hfov: float,
        vfov: float,
        motion: Motion | None = None,
        radiance: float = 1.0,
    ) -> np.ndarray:
        """Turn a clean rendered frame into the camera's frame.

        Args:
            rgb: ``(h, w, 3)`` uint8 RGB pinhole render (principal point at the centre).
            time_s: Simulated time of the frame (s); AE and AWB run at ``fps`` between frames.
            fps: Frame rate of the subscription (frames/s).
            hfov: Horizontal field of view of the render (rad).
            vfov: Vertical field of view of the render (rad).
            motion: The camera's velocity during the exposure (optical frame), or None.
            radiance: The scene's radiance over the render's (>= 1: a room lit brighter
                than the renderer can shade); the exposure sees ``rgb`` times this.

        Returns:
            ``(h, w, 3)`` uint8 RGB: the input itself under the ``ideal`` profile, else a new
            array.
        """
        s = self.settings
        if s.identity:  # a fixed exposure: a brighter room is a brighter picture
            return rgb if radiance == 1.0 else cv2.convertScaleAbs(rgb, alpha=radiance)
        height, width = rgb.shape[:2]
        geo = self._geometry_for(width, height, hfov, vfov)
        frames = self._frames_since(time_s, fps)
        self._last_time = time_s
        small = cv2.resize(rgb, (40, 30), interpolation=cv2.INTER_AREA).astype(np.float32)
        luma_small = (small @ _LUMA) * geo.vignette_small
        if radiance != 1.0:
            luma_small = luma_small * np.float32(radiance)
        total = self._update_exposure(luma_small, frames, fps) * radiance
        awb = self._update_white_balance(small, frames)

        # Image velocity of the scene at the image centre (px/s), from the camera's motion.
        flow = (0.0, 0.0)
        if motion is not None:
            (wx, wy, _), (vx, vy, _) = motion.omega, motion.velocity
            f = geo.focal
            flow = (-f * (wy + vx / BLUR_DEPTH_M), f * (wx - vy / BLUR_DEPTH_M))

        img = rgb
        if s.rolling_shutter and flow != (0.0, 0.0):
            rows = np.arange(height, dtype=np.float32)
            tau = (rows / max(1, height - 1) - 0.5) * (ROLLING_SHUTTER_FRAMES / fps)
            map_x = geo.map_x - np.float32(flow[0]) * tau[:, None]
            map_y = geo.map_y - np.float32(flow[1]) * tau[:, None]
            img = cv2.remap(img, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        elif s.distortion:
            img = cv2.remap(img, *geo.fixed, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        if s.motion_blur:
            du, dv = flow[0] * self.exposure_s, flow[1] * self.exposure_s
            img = motion_blur(img, du, dv)
        if s.blur_px > 0:
            img = cv2.GaussianBlur(img, (0, 0), s.blur_px)

        if np.any(np.abs(awb - 1.0) > 1e-3):
            img = cv2.transform(img, np.diag(awb * np.float32(total)).astype(np.float32))
            total = 1.0
        if s.vignetting > 0:
            img = cv2.multiply(img, geo.vignette, scale=total, dtype=cv2.CV_8U)
        elif total != 1.0:
            img = cv2.convertScaleAbs(img, alpha=total)  # a positive gain: abs changes nothing
        if s.sensor_noise or s.yuv422 or s.noise_std > 0:
            img = self._sensor_and_chroma(img, geo)
        result = img if img is not rgb else rgb.copy()
        if s.jpeg_quality is not None:
            ok, buf = cv2.imencode(
                ".jpg", result[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, s.jpeg_quality]
            )
            decoded = cv2.imdecode(buf, cv2.IMREAD_COLOR) if ok else None
            if decoded is not None:
                result = np.ascontiguousarray(decoded[..., ::-1])
        return result

    def _sensor_and_chroma(self, rgb: np.ndarray, geo: _Geometry) -> np.ndarray:
        """Add sensor noise in YUV and halve the chroma horizontally (uint8 RGB in and out).

        Sensor noise: variance in DN^2 of shot noise ``L g / (e/DN)`` plus read noise
        ``(e_read g / (e/DN))^2`` at luma ``L`` and analog gain ``g``; chroma noise is
        ``CHROMA_NOISE`` times as large, one sample per pixel pair under YUV422.
        """
        s = self.settings
        height, width = rgb.shape[:2]
        planes = list(cv2.split(cv2.cvtColor(rgb, cv2.COLOR_RGB2YUV)))
        dy, dx = (int(v) for v in self._rng.integers(0, _BANK_MARGIN, 2))
        std: np.ndarray | None = None
        if s.sensor_noise:
            e_per_dn = FULL_WELL_E / 255.0
            read = np.float32((READ_NOISE_E * self.gain / e_per_dn) ** 2)
            luma = planes[0].astype(np.float32)
            std = cv2.sqrt(luma * np.float32(self.gain / e_per_dn) + read)
        elif s.noise_std > 0:
            std = np.full((height, width), s.noise_std, np.float32)
        if std is not None:
            noise = cv2.multiply(geo.noise_y[dy : dy + height, dx : dx + width], std)
            planes[0] = cv2.add(planes[0], noise, dtype=cv2.CV_8U)
        pairs = s.yuv422 and width % 2 == 0
        if not pairs and std is None:
            return cv2.cvtColor(cv2.merge(planes), cv2.COLOR_YUV2RGB)
        size = (width // 2, height) if pairs else (width, height)
        if std is not None:
            cstd = cv2.resize(std, size, interpolation=cv2.INTER_AREA) if pairs else std
            cstd = cstd * np.float32(CHROMA_NOISE)
        for k in (1, 2):
            plane = planes[k]
            if pairs:
                plane = cv2.resize(plane, size, interpolation=cv2.INTER_AREA)
            if std is not None:
                bank = geo.noise_c[k - 1]
                noise = cv2.multiply(bank[dy : dy + size[1], dx : dx + size[0]], cstd)
                plane = cv2.add(plane, noise, dtype=cv2.CV_8U)
            if pairs:
                plane = cv2.resize(plane, (width, height), interpolation=cv2.INTER_NEAREST)
            planes[k] = plane
        return cv2.cvtColor(cv2.merge(planes), cv2.COLOR_YUV2RGB)
