"""The simulation: a NAO in a generated room, stepped one ALMotion cycle (20 ms) at a time.

Frames: the room frame (origin at a room corner, x and y along the walls) is MuJoCo's world
frame; the base joints ``base_x, base_y, base_yaw`` are the robot's true pose in it.
FRAME_WORLD (odometry) starts at the robot's pose when the simulation is created, and is
never told about teleports.

Walking is open-loop on odometry, as on a NAO: the walk controller steers on the sensor
odometry, each cycle's odometry increment goes through
:class:`naoloc.backends.simulated.odometry.OdometryModel` (``world.odometry``), and the base is
driven at the true velocity the model returns, so physics (walls, furniture) decides where
the body goes while the odometry keeps counting what the legs did.

Time is simulated only: nothing here reads the wall clock except the optional real-time
pacing (``world.sim.realtime``). Every call of :meth:`Simulation.cycle` advances the
physics by one ALMotion cycle. The same config gives the same run, step for step.

:class:`Simulation` implements :class:`naoloc.robot.SimControl` plus a few extras for
robustness experiments (lights, posters, a marker); see ``naoloc/backends/mujoco/README.md``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from naoloc.backends.mujoco.gl import import_mujoco
from naoloc.backends.mujoco.nao import (
    NAO_XML,
    POSTURES,
    ROBOT_RADIUS,
    STANDING_POSTURES,
)
from naoloc.backends.mujoco.room import RoomLayout, build_layout, room_mjcf
from naoloc.backends.mujoco.walk import WalkController, WalkLimits
from naoloc.backends.simulated.camera_model import render_fov_for
from naoloc.backends.simulated.odometry import OdometryModel
from naoloc.backends.simulated.sway import WalkSway
from naoloc.config import Config
from naoloc.constants import FOV_V5, FOV_V6, JOINT_NAMES, MOTION_CYCLE_S
from naoloc.errors import BackendError, RobotError
from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse
from naoloc.robot import kinematics
from naoloc.robot.kinematics import head_pitch_limits

# mujoco reads MUJOCO_GL when first imported: import_mujoco chooses the platform first.
mujoco: Any = import_mujoco()

CAMERA_NAMES = ("CameraTop", "CameraBottom")
_LEG_JOINTS = tuple(n for n in JOINT_NAMES if n[1:4] in ("Hip", "Kne", "Ank"))
# MuJoCo's camera frame (looks along -z, x right, y up) -> NAOqi's (x along the view, y left).
_GL_TO_NAOQI = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
_GAIT_HZ = 1.0  # strides per second: two steps per second, NAO's maximum step frequency
_GAIT_AMPLITUDE = 0.18  # rad of hip flexion at full speed (a visible, not a dynamic, gait)


def _obj_id(model: Any, kind: Any, name: str) -> int:
    idx = int(mujoco.mj_name2id(model, kind, name))
    if idx < 0:
        raise BackendError(f"the NAO model has no {kind.name.lower()[6:]} named {name!r}")
    return idx


def fill_textures(model: Any, layout: RoomLayout) -> None:
    """Copy the generated pixels into the compiled model's flat placeholder textures."""
    images = {"wall": layout.wall_image, "floor": layout.floor_image}
    images.update({p.name: p.image for p in layout.posters})
    images.update(layout.materials)  # textures of home and office rooms (wood, fabric...)
    for name, image in images.items():
        i = _obj_id(model, mujoco.mjtObj.mjOBJ_TEXTURE, name)
        adr, w, h = int(model.tex_adr[i]), int(model.tex_width[i]), int(model.tex_height[i])
        n = w * h * int(model.tex_nchannel[i])
        model.tex_data[adr : adr + n] = np.ascontiguousarray(image, dtype=np.uint8).reshape(-1)


class Simulation:
    """MuJoCo model and data of the NAO in its room, with the walk and the odometry.

    Attributes:
        cfg: The config the world was built from.
        layout: The generated room.
        model: ``mujoco.MjModel``.
        data: ``mujoco.MjData``.
        walk: The walk controller (move tasks).
        cycle_s: Simulated seconds per ALMotion cycle (a whole number of physics steps).
    """

    def __init__(self, cfg: Config) -> None:
        """Build the room, compile it with the NAO, and stand the robot at the start pose.

        Raises:
            BackendError: If the generated MJCF does not compile.
        """
        self.cfg = cfg
        self.layout = build_layout(cfg)
        xml = room_mjcf(self.layout, cfg.world.sim.timestep_s)
        try:
            self.model = mujoco.MjModel.from_xml_string(
                xml, assets={"nao.xml": NAO_XML.read_bytes()}
            )
        except ValueError as err:
            first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
            raise BackendError(f"the simulated room does not compile: {first}") from None
        fill_textures(self.model, self.layout)
        fov = FOV_V6 if cfg.world.model == "v6" else FOV_V5
        self.fov = (float(fov[0]), float(fov[1]))  # what ALVideoDevice reports
        # what is rendered: wider when the camera images through NAO's lens
        self.render_fov = render_fov_for(self.fov, cfg.world.camera_realism)
        wide = self.render_fov
        for name in CAMERA_NAMES:
            cam = _obj_id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, name)
            self.model.cam_sensorsize[cam] = [2 * math.tan(wide[0] / 2), 2 * math.tan(wide[1] / 2)]
        self.data = mujoco.MjData(self.model)
        self.substeps = max(1, round(MOTION_CYCLE_S / self.model.opt.timestep))
        self.cycle_s = self.substeps * float(self.model.opt.timestep)
        self._init_joints()
        self._tune_gains()
        self._light0 = (self.model.light_diffuse.copy(), self.model.light_ambient.copy())
        self._head0 = (
            np.array(self.model.vis.headlight.ambient),
            np.array(self.model.vis.headlight.diffuse),
        )
        self.radiance = 1.0  # scene radiance over the rendered frame's (set_light_scale)
        self.set_light_scale(1.0)  # applies world.sim.light
        self._poster0 = {p.name: p for p in self.layout.posters}
        self._poster_pos0 = {
            p.name: self.model.geom_pos[self._poster_geom(p.name)].copy()
            for p in self.layout.posters
        }
        self.walk = WalkController(WalkLimits(), self.cycle_s)
        self.odometry = OdometryModel(cfg.world.odometry)
        self.sway = WalkSway(cfg.world.sim.camera_sway)
        self.command_velocity = (0.0, 0.0, 0.0)
        self._gait_phase = 0.0
        self.posture_name = "StandInit"
        self.set_posture_now("StandInit")
        x, y, th = cfg.start_pose()
        self._place(x, y, th)
        self.closed = False
        self._realtime = cfg.world.sim.realtime
        self._wall0 = time.monotonic()
        self._sim0 = float(self.data.time)
        self.clock: Any = (
            None  # a naoloc.backends.naoqi.emulation.loop.SimClock when served in real time
        )

    @property
    def command_odometry(self) -> Pose2D:
        """Integrated commands (``getRobotPosition(False)``), FRAME_WORLD."""
        return self.odometry.command

    @property
    def sensor_odometry(self) -> Pose2D:
        """Sensor odometry (``getRobotPosition(True)``), FRAME_WORLD."""
        return self.odometry.sensor

    # ----------------------------------------------------------------------------- joints
    def _init_joints(self) -> None:
        m = self.model
        self.joint_names = JOINT_NAMES
        self.joint_index = {n: i for i, n in enumerate(JOINT_NAMES)}
        jids = [_obj_id(m, mujoco.mjtObj.mjOBJ_JOINT, n) for n in JOINT_NAMES]
        self._qadr = np.array([m.jnt_qposadr[j] for j in jids])
        self.limits = np.array([m.jnt_range[j] for j in jids], dtype=np.float64)
        self.max_speed = np.array(
            [float(m.numeric(f"speed/{n}").data[0]) for n in JOINT_NAMES], dtype=np.float64
        )
        acts = [int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, n)) for n in JOINT_NAMES]
        self._act_mask = np.array([a >= 0 for a in acts])
        self._act_ids = np.array([a for a in acts if a >= 0])
        self._walk_ids = [
            _obj_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, n) for n in ("walk_x", "walk_y", "walk_yaw")
        ]
        self._torso_body = _obj_id(m, mujoco.mjtObj.mjOBJ_BODY, "torso")
        self._cam_ids = [_obj_id(m, mujoco.mjtObj.mjOBJ_CAMERA, n) for n in CAMERA_NAMES]
        self._lhip = self.joint_index["LHipPitch"]
        self._lknee = self.joint_index["LKneePitch"]
        self._r_hyp = self.joint_index["RHipYawPitch"]
        self._l_hyp = self.joint_index["LHipYawPitch"]
        self._head_yaw = self.joint_index["HeadYaw"]
        self._head_pitch = self.joint_index["HeadPitch"]
        n = len(JOINT_NAMES)
        self.target = np.zeros(n)
        self.command = np.zeros(n)
        self.rate = self.max_speed.copy()
        self.stiffness = np.ones(n)

    def _tune_gains(self) -> None:
        """Keep the joint servos stable for the configured step: natural frequency <= 0.6/dt."""
        m = self.model
        dt = float(m.opt.timestep)
        omega_max = 0.6 / dt
        for a in self._act_ids:
            kp = float(m.actuator_gainprm[a, 0])
            kv = -float(m.actuator_biasprm[a, 2])
            inertia = kv * kv / (4.0 * kp)  # from dampratio = 1: kv = 2 sqrt(kp I)
            if math.sqrt(kp / inertia) > omega_max:
                kp = inertia * omega_max**2
                kv = 2.0 * inertia * omega_max
            m.actuator_gainprm[a, 0] = kp
            m.actuator_biasprm[a, 1] = -kp
            m.actuator_biasprm[a, 2] = -kv
        self._kp0 = m.actuator_gainprm[self._act_ids, 0].copy()

    def apply_stiffness(self) -> None:
        """Scale every joint servo's gain by its stiffness in [0, 1]."""
        kp = self._kp0 * np.clip(self.stiffness[self._act_mask], 0.0, 1.0)
        self.model.actuator_gainprm[self._act_ids, 0] = kp
        self.model.actuator_biasprm[self._act_ids, 1] = -kp

    @property
    def awake(self) -> bool:
        """True when the leg joints are stiff (NAOqi's robotIsWakeUp)."""
        legs = [self.joint_index[n] for n in _LEG_JOINTS]
        return bool(np.all(self.stiffness[legs] > 0.0))

    def set_joint_targets(self, names: list[str], angles: list[float], fraction: float) -> None:
        """Move joints toward angles (rad, clipped to limits) at ``fraction`` of max speed."""
        idx = [self.joint_index[n] for n in names]
        if "RHipYawPitch" in names and "LHipYawPitch" not in names:
            idx = [self._l_hyp if i == self._r_hyp else i for i in idx]  # one shared motor
        for i, a in zip(idx, angles, strict=True):
            lo, hi = self.limits[i]
            self.target[i] = min(hi, max(lo, float(a)))
            self.rate[i] = self.max_speed[i] * fraction
        self.target[self._r_hyp] = self.target[self._l_hyp]
        self.rate[self._r_hyp] = self.rate[self._l_hyp]
        lo, hi = head_pitch_limits(float(self.target[self._head_yaw]))
        self.target[self._head_pitch] = min(hi, max(lo, float(self.target[self._head_pitch])))

    def joint_angles(self, names: list[str], use_sensors: bool) -> list[float]:
        """Joint angles in radians: measured (qpos) or commanded."""
        idx = [self.joint_index[n] for n in names]
        if use_sensors:
            return [float(self.data.qpos[self._qadr[i]]) for i in idx]
        return [float(self.command[i]) for i in idx]

    def joints_settled(self, names: list[str], tol: float = 0.01) -> bool:
        """True when the commands reached their targets and the joints followed within ``tol``."""
        idx = [self.joint_index[n] for n in names]
        stiff = [i for i in idx if self.stiffness[i] > 0]
        if np.any(np.abs(self.command[idx] - self.target[idx]) > 1e-9):
            return False
        q = self.data.qpos[self._qadr[stiff]]
        return bool(np.all(np.abs(q - self.command[stiff]) < tol))

    def set_posture_now(self, name: str) -> None:
        """Put the joints in a posture instantly (at start-up only)."""
        angles = POSTURES[name]
        for n, a in angles.items():
            i = self.joint_index[n]
            self.target[i] = self.command[i] = a
            self.data.qpos[self._qadr[i]] = a
        self.posture_name = name
        self.place_torso()
        self._write_joint_ctrl()
        mujoco.mj_forward(self.model, self.data)

    def detect_posture(self) -> str:
        """The predefined posture the legs are in (0.1 rad tolerance), or "Unknown".

        The last posture gone to wins among postures with the same legs (StandZero and
        the lying postures, since the model does not lie down). While the robot walks, the
        legs' stance (their commands, without the gait's swing) decides, as NAO reports
        "Standing" while it walks.
        """
        q = self.command if self._gait_phase != 0.0 else self.data.qpos[self._qadr]
        legs = [self.joint_index[n] for n in _LEG_JOINTS]
        names = [self.posture_name, *(n for n in POSTURES if n != self.posture_name)]
        for name in names:
            if name not in POSTURES:
                continue
            ref = np.array([POSTURES[name][self.joint_names[i]] for i in legs])
            if np.all(np.abs(q[legs] - ref) < 0.1):
                return name
        return "Unknown"

    def fk_angles(self, use_sensors: bool) -> dict[str, float]:
        """Joint angles (rad) for the forward kinematics: measured or commanded.

        The legs' gait swing (visual) is left out: the torso's pose comes from the stance legs
        (the commanded posture) plus the walk's sway.
        """
        angles = dict(zip(JOINT_NAMES, (float(v) for v in self.command), strict=True))
        if use_sensors:
            q = self.data.qpos[self._qadr]
            walking = self._gait_phase != 0.0
            for i, n in enumerate(JOINT_NAMES):
                if not (walking and n in _LEG_JOINTS):
                    angles[n] = float(q[i])
        return angles

    def torso_in_robot(self, use_sensors: bool = True) -> np.ndarray:
        """The torso's 4x4 pose in FRAME_ROBOT: legs' kinematics, plus the sway if sensed."""
        t = kinematics.robot_to_torso(self.fk_angles(use_sensors))
        offset = self.sway.torso_offset() if use_sensors else None
        return t if offset is None else offset @ t

    def place_torso(self) -> None:
        """Put the torso body where the kinematics (and the sway) say (model pos and quat)."""
        t = self.torso_in_robot(True)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(t[:3, :3]).reshape(-1))
        self.model.body_pos[self._torso_body] = t[:3, 3]
        self.model.body_quat[self._torso_body] = quat

    def true_camera_pose(self, camera_index: int = 0) -> list[float]:
        """True pose of a camera, room frame: ``[x, y, z, wx, wy, wz]`` (m, rad).

        The frame is NAOqi's camera frame (x along the view, y left, z up); the angles are
        ALMotion.getPosition's roll-pitch-yaw, so ``wy > 0`` looks down.

        Raises:
            RobotError: For a camera index other than 0 (top) or 1 (bottom).
        """
        if camera_index not in (0, 1):
            raise RobotError(f"camera index {camera_index} does not exist (0 top, 1 bottom)")
        mujoco.mj_kinematics(self.model, self.data)
        cam = self._cam_ids[camera_index]
        rot = self.data.cam_xmat[cam].reshape(3, 3) @ _GL_TO_NAOQI
        return kinematics.position6d(kinematics.homogeneous(rot, self.data.cam_xpos[cam]))

    def _write_joint_ctrl(self, gait: np.ndarray | None = None) -> None:
        q = self.command if gait is None else self.command + gait
        self.data.ctrl[self._act_ids] = q[self._act_mask]

    # ----------------------------------------------------------------------------- stepping
    def cycle(self, n: int = 1) -> None:
        """Advance the simulation by ``n`` ALMotion cycles (``n * cycle_s`` seconds).

        Raises:
            RobotError: Once the robot was closed (every service call passes here).
        """
        if self.closed:
            raise RobotError("the simulated robot is closed")
        if self.clock is not None:
            self.clock.advance(n)
            return
        for _ in range(n):
            self._one_cycle()
        if self._realtime:
            ahead = (float(self.data.time) - self._sim0) - (time.monotonic() - self._wall0)
            if ahead > 0:
                time.sleep(ahead)

    def _one_cycle(self) -> None:
        m, d = self.model, self.data
        start = self.true_pose2d()
        if not self.awake and self.walk.active:
            self.walk.stop()
        cmd = self.walk.command(self.sensor_odometry)
        self.command_velocity = cmd
        dt = self.cycle_s
        step = self.rate * dt
        self.command += np.clip(self.target - self.command, -step, step)
        lo, hi = head_pitch_limits(float(self.command[self._head_yaw]))  # the shell, on the way
        self.command[self._head_pitch] = min(hi, max(lo, float(self.command[self._head_pitch])))
        self._write_joint_ctrl(self._gait_offsets(cmd, dt))
        vx, vy, wz = self._true_twist(cmd, dt)
        ix, iy, iw = self._walk_ids
        for _ in range(self.substeps):
            yaw = float(d.qpos[2])
            c, s = math.cos(yaw), math.sin(yaw)
            d.ctrl[ix] = c * vx - s * vy
            d.ctrl[iy] = s * vx + c * vy
            d.ctrl[iw] = wz
            mujoco.mj_step(m, d)
        moved = pose2DInverse(start) * self.true_pose2d()
        self.walk.observe(cmd, moved)
        self.sway.step(any(v != 0.0 for v in cmd) and self.awake, dt)
        self.place_torso()

    def _true_twist(self, cmd: tuple[float, float, float], dt: float) -> tuple[float, float, float]:
        """Count a commanded twist in the odometry; the body's true twist (FRAME_ROBOT)."""
        vx, vy, wz = cmd
        if vx == 0.0 and vy == 0.0 and wz == 0.0:
            return cmd
        half = wz * dt / 2
        c, s = math.cos(half), math.sin(half)
        odo = Pose2D((c * vx - s * vy) * dt, (s * vx + c * vy) * dt, wz * dt)
        true = self.odometry.walk(odo)
        wt = true.theta / dt
        c, s = math.cos(wt * dt / 2), math.sin(wt * dt / 2)
        return ((c * true.x + s * true.y) / dt, (-s * true.x + c * true.y) / dt, wt)

    def _gait_offsets(self, cmd: tuple[float, float, float], dt: float) -> np.ndarray | None:
        lim = self.walk.limits
        effort = max(abs(cmd[0]) / lim.vx, abs(cmd[1]) / lim.vy, abs(cmd[2]) / lim.wz)
        if effort <= 0.0 or self.posture_name not in STANDING_POSTURES:
            self._gait_phase = 0.0
            return None
        self._gait_phase = (self._gait_phase + 2 * math.pi * _GAIT_HZ * dt) % (2 * math.pi)
        out = np.zeros(len(self.joint_names))
        amp = _GAIT_AMPLITUDE * min(1.0, effort)
        for side, phase in (("L", 0.0), ("R", math.pi)):
            lift = amp * max(0.0, math.sin(self._gait_phase + phase))
            out[self.joint_index[f"{side}HipPitch"]] = -lift
            out[self.joint_index[f"{side}KneePitch"]] = 2 * lift
            out[self.joint_index[f"{side}AnklePitch"]] = -lift
        return out

    def attach_clock(self, clock: Any) -> tuple[Callable[[], None], float]:
        """Let a real-time clock drive time (``naoloc serve``); None = deterministic again.

        Returns:
            The function that runs one ALMotion cycle, and the cycle length in seconds.
        """
        self.clock = clock
        return self._one_cycle, self.cycle_s

    def close(self) -> None:
        """Stop the walk and refuse further service calls; safe to call twice."""
        self.walk.stop()
        self.closed = True

    def prepare_render(self) -> None:
        """Bring body, camera and light poses up to date with qpos (before rendering)."""
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)

    def warnings(self) -> dict[str, int]:
        """MuJoCo warnings raised so far, by name (empty when the simulation is healthy)."""
        out = {}
        for i, stat in enumerate(self.data.warning):
            if stat.number > 0:
                out[mujoco.mjtWarning(i).name] = int(stat.number)
        return out

    # ----------------------------------------------------------------------------- SimControl
    def true_pose2d(self) -> Pose2D:
        """Ground-truth robot pose in the room frame as a Pose2D (theta not wrapped)."""
        q = self.data.qpos
        return Pose2D(float(q[0]), float(q[1]), float(q[2]))

    def true_pose(self) -> tuple[float, float, float]:
        """Ground-truth ``(x, y, theta)`` of the robot (FRAME_ROBOT origin), room frame."""
        q = self.data.qpos
        return (float(q[0]), float(q[1]), modulo2PI(float(q[2])))

    def _place(self, x: float, y: float, theta: float) -> None:
        d = self.data
        d.qpos[0:3] = [x, y, modulo2PI(theta)]
        d.qvel[:] = 0.0
        d.ctrl[self._walk_ids] = 0.0
        mujoco.mj_forward(self.model, d)

    def teleport(self, x: float, y: float, theta: float) -> None:
        """Put the robot at ``(x, y, theta)`` in the room frame; odometry is not told.

        Raises:
            RobotError: If the robot's body would overlap a wall or a piece of furniture.
        """
        if not all(math.isfinite(v) for v in (x, y, theta)):
            raise RobotError(f"teleport target {[x, y, theta]} is not finite")
        if not self.layout.is_free(x, y, ROBOT_RADIUS):
            raise RobotError(
                f"cannot teleport to ({x:.3f}, {y:.3f}): the robot (radius {ROBOT_RADIUS} m) "
                "would overlap a wall or furniture"
            )
        self.walk.stop()
        self.command_velocity = (0.0, 0.0, 0.0)
        self._place(x, y, theta)

    def room_size(self) -> tuple[float, float]:
        """Inner size of the room ``(x, y)`` in metres."""
        return self.layout.size

    def is_free(self, x: float, y: float, clearance: float) -> bool:
        """True when a disc of ``clearance`` m at ``(x, y)`` touches no wall or furniture."""
        return self.layout.is_free(x, y, clearance)

    def sim_time(self) -> float:
        """Simulated seconds since the backend started."""
        return float(self.data.time)

    # ----------------------------------------------------------------------------- extras
    def set_light_scale(self, scale: float) -> None:
        """Scale every room light and the ambient light by ``scale`` (1 = as configured).

        Up to 1 (with ``world.sim.light``) the lights themselves are scaled. Beyond 1 the
        scene is rendered at 1 and :attr:`radiance` (the excess) multiplies what reaches
        the camera model, before its exposure: MuJoCo clamps each surface's lighting at 1,
        so brighter lights would wash out the contrast between floor and walls (a floor
        lit from above saturates first) where a real room's radiances only scale, and a
        camera's auto exposure gives back the same picture. Windows' daylight (emission)
        scales with it too.
        """
        if not (math.isfinite(scale) and scale >= 0):
            raise RobotError(f"light scale must be a finite number >= 0, got {scale}")
        k = scale * self.cfg.world.sim.light
        shade = min(k, 1.0)
        self.radiance = max(k, 1.0)
        self.model.light_diffuse[:] = self._light0[0] * shade
        self.model.light_ambient[:] = self._light0[1] * shade
        self.model.vis.headlight.ambient[:] = self._head0[0] * shade
        self.model.vis.headlight.diffuse[:] = self._head0[1] * shade

    def poster_names(self) -> list[str]:
        """Names of all posters, ``poster_<wall>_<k>`` with wall in x0, x1, y0, y1."""
        return [p.name for p in self.layout.posters]

    def _poster_geom(self, name: str) -> int:
        if name not in self._poster0:
            raise RobotError(f"no poster named {name!r}; see poster_names()")
        return int(mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, name))

    def move_poster(self, name: str, dx: float, dz: float = 0.0) -> None:
        """Slide a poster ``dx`` m along its wall (and ``dz`` m up) from where it was built.

        Along the wall means +y on walls x0 and x1, +x on walls y0 and y1 (room frame).
        """
        g = self._poster_geom(name)
        pos = self._poster_pos0[name].copy()
        pos[1 if self._poster0[name].wall in ("x0", "x1") else 0] += dx
        pos[2] += dz
        self.model.geom_pos[g] = pos

    def remove_poster(self, name: str) -> None:
        """Take a poster off its wall (it is no longer rendered)."""
        self.model.geom_group[self._poster_geom(name)] = 5

    def restore_poster(self, name: str) -> None:
        """Hang a removed or moved poster back where it was built."""
        g = self._poster_geom(name)
        self.model.geom_group[g] = 0
        self.model.geom_pos[g] = self._poster_pos0[name]

    def set_marker(self, x: float, y: float, z: float) -> None:
        """Show a small red sphere (radius 1 cm, unlit colour) at a room-frame point (m)."""
        self.data.mocap_pos[0] = [x, y, z]

    def hide_marker(self) -> None:
        """Hide the marker (below the floor)."""
        self.data.mocap_pos[0] = [0.0, 0.0, -1.0]
