"""ceilpose: read the robot pose that ceilposed publishes in shared memory.

A thin ctypes layer over the C client (libceilpose_client.so.3, ABI 3), so
nothing is compiled on install::

    import ceilpose
    with ceilpose.Client("/ceilpose") as client:
        pose = client.wait_next(timeout_s=1.0)   # the next frame's pose
        now = client.predict()                   # where the robot is now
        print(now.x_m, now.y_m, now.yaw_rad, now.vx_mps)
        for name, other in client.fleet(time.monotonic_ns()).items():
            print(name, other.x_m, other.y_m, other.age_ms, other.stale)

Times are CLOCK_MONOTONIC nanoseconds, as time.monotonic_ns() gives them on
Linux. Every failure raises CeilposeError with the C client's code, its name
and its message (which names the segment). docs/ipc.md describes the segment,
docs/fleet.md the fleet segment behind Client.fleet().
"""

import ctypes
import ctypes.util
import math
import os
import time

__all__ = ["Client", "Pose", "FleetPose", "CeilposeError", "ABI_VERSION", "FLEET_ABI_VERSION",
           "DEFAULT_SHM"]

ABI_VERSION = 3
FLEET_ABI_VERSION = 1
DEFAULT_SHM = "/ceilpose"
_SONAME = "libceilpose_client.so.3"
_STATE = 9

_FLAG_VALID = 0x1
_FLAG_FILTERED = 0x2
_FLAG_COASTING = 0x4
_FLAG_MOTION = 0x8
_FLEET_STALE = 0x1
_FLEET_PREDICTED = 0x2
_ROBOT_NAME_SIZE = 64
_INT64_MIN, _INT64_MAX = -2**63, 2**63 - 1

_ERRORS = {
    -1: "INVALID_ARGUMENT", -2: "NOT_FOUND", -3: "PERMISSION", -4: "ABI_MISMATCH",
    -5: "BAD_SIZE", -6: "BAD_MAGIC", -7: "NOT_READY", -8: "SYSTEM", -9: "NO_MEMORY",
    -10: "NO_POSE", -11: "BUSY", -12: "TIMEOUT", -13: "STOPPED", -14: "WRITER_DEAD",
    -15: "LIVE_WRITER", -16: "NO_GROUP", -17: "NO_MOTION", -18: "HORIZON",
}


class _PoseRecord(ctypes.Structure):
    """The bytes of ceilpose_pose (ipc/include/ceilpose/pose_client.h)."""

    _fields_ = [
        ("seq", ctypes.c_uint64),
        ("capture_mono_ns", ctypes.c_int64),
        ("capture_real_ns", ctypes.c_int64),
        ("publish_mono_ns", ctypes.c_int64),
        ("publish_real_ns", ctypes.c_int64),
        ("x_m", ctypes.c_double),
        ("y_m", ctypes.c_double),
        ("yaw_rad", ctypes.c_double),
        ("covariance", ctypes.c_double * 9),
        ("flags", ctypes.c_uint32),
        ("mode", ctypes.c_uint8),
        ("refusal", ctypes.c_uint8),
        ("markers", ctypes.c_uint16),
        ("vx_mps", ctypes.c_double),
        ("vy_mps", ctypes.c_double),
        ("yaw_rate_radps", ctypes.c_double),
        ("ax_mps2", ctypes.c_double),
        ("ay_mps2", ctypes.c_double),
        ("yaw_accel_radps2", ctypes.c_double),
        ("state_covariance", ctypes.c_double * (_STATE * _STATE)),
        ("jerk_density", ctypes.c_double * 3),
        ("predict_horizon_ms", ctypes.c_uint32),
        ("reserved0", ctypes.c_uint32),
    ]


class _FleetRecord(ctypes.Structure):
    """The bytes of ceilpose_fleet_robot."""

    _fields_ = [
        ("robot", ctypes.c_char * _ROBOT_NAME_SIZE),
        ("pose", _PoseRecord),
        ("received_mono_ns", ctypes.c_int64),
        ("latency_ns", ctypes.c_int64),
        ("samples", ctypes.c_uint64),
        ("fleet_flags", ctypes.c_uint32),
        ("lost", ctypes.c_uint32),
    ]


class _FleetInfo(ctypes.Structure):
    """The bytes of ceilpose_fleet_info."""

    _fields_ = [
        ("pid", ctypes.c_int32),
        ("state", ctypes.c_uint32),
        ("generation", ctypes.c_uint64),
        ("heartbeat_mono_ns", ctypes.c_int64),
        ("capacity", ctypes.c_uint32),
        ("robots", ctypes.c_uint32),
        ("stale_after_ms", ctypes.c_uint32),
        ("reserved0", ctypes.c_uint32),
        ("accepted", ctypes.c_uint64),
        ("refused_full", ctypes.c_uint64),
        ("refused_future", ctypes.c_uint64),
        ("refused_past", ctypes.c_uint64),
        ("refused_invalid", ctypes.c_uint64),
        ("refused_duplicate", ctypes.c_uint64),
        ("removed", ctypes.c_uint64),
    ]


# The header's own layout checks, repeated: a mismatch must fail at import.
if ctypes.sizeof(_PoseRecord) != 872 or _PoseRecord.state_covariance.offset != 192:
    raise ImportError("ceilpose: ctypes layout of ceilpose_pose does not match ABI 3")
if ctypes.sizeof(_FleetRecord) != 968 or _FleetRecord.latency_ns.offset != 944 or \
        ctypes.sizeof(_FleetInfo) != 96:
    raise ImportError("ceilpose: ctypes layout of the fleet records does not match fleet ABI 1")


def _whole(value, name, low, high, unit):
    """`value` as an int within [low, high], else ValueError naming `name`:
    ctypes would wrap it silently (2**64 + t becomes t)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name} must be a number of {unit}, not {value!r}")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{name} must be finite, not {value}")
    if not low <= value <= high:
        raise ValueError(f"{name} = {value} {unit} is outside {low}..{high}")
    return int(value)


def _instant(t_mono_ns, name):
    """A CLOCK_MONOTONIC instant the C calls take (int64 ns)."""
    return _whole(t_mono_ns, name, _INT64_MIN, _INT64_MAX, "ns")


class CeilposeError(Exception):
    """A C client failure: .code (negative int), .name ("NOT_FOUND", ...)."""

    def __init__(self, code, message):
        self.code = code
        self.name = _ERRORS.get(code, "UNKNOWN")
        super().__init__(message)


def _load_library():
    # CEILPOSE_CLIENT_LIBRARY names the .so (a build tree); else the installed
    # soname, which pins the ABI this module speaks.
    path = os.environ.get("CEILPOSE_CLIENT_LIBRARY") or _SONAME
    try:
        lib = ctypes.CDLL(path)
    except OSError as e:
        raise ImportError(
            f"ceilpose: cannot load the C client {path}: {e} "
            "(install the ceilpose package, or set CEILPOSE_CLIENT_LIBRARY)") from e
    handle = ctypes.c_void_p
    pose_p = ctypes.POINTER(_PoseRecord)
    signatures = {
        "ceilpose_client_open": ([ctypes.c_char_p, ctypes.POINTER(handle)], ctypes.c_int),
        "ceilpose_client_close": ([handle], None),
        "ceilpose_client_read_latest": ([handle, pose_p], ctypes.c_int),
        "ceilpose_client_wait_next": ([handle, ctypes.c_uint64, ctypes.c_int32, pose_p],
                                      ctypes.c_int),
        "ceilpose_client_predict": ([handle, ctypes.c_int64, pose_p], ctypes.c_int),
        "ceilpose_client_fleet_open": ([ctypes.c_char_p, ctypes.POINTER(handle)], ctypes.c_int),
        "ceilpose_client_fleet_close": ([handle], None),
        "ceilpose_client_fleet_read": ([handle, ctypes.c_int64, ctypes.POINTER(_FleetRecord),
                                        ctypes.c_uint32, ctypes.POINTER(ctypes.c_uint32)],
                                       ctypes.c_int),
        "ceilpose_client_fleet_info": ([handle, ctypes.POINTER(_FleetInfo)], ctypes.c_int),
        "ceilpose_strerror": ([ctypes.c_int], ctypes.c_char_p),
        "ceilpose_last_error_message": ([], ctypes.c_char_p),
        "ceilpose_mode_name": ([ctypes.c_uint8], ctypes.c_char_p),
        "ceilpose_refusal_name": ([ctypes.c_uint], ctypes.c_char_p),
    }
    for name, (args, result) in signatures.items():
        fn = getattr(lib, name)
        fn.argtypes = args
        fn.restype = result
    return lib


_lib = _load_library()


def _raise(code, what):
    detail = _lib.ceilpose_last_error_message().decode(errors="replace")
    text = _lib.ceilpose_strerror(code).decode()
    raise CeilposeError(code, f"{what}: {text}" + (f" ({detail})" if detail else ""))


class Pose:
    """One pose: position in `map` (metres), yaw (radians, CCW from East),
    the filter's world-frame velocity, their covariances (3x3 row-major
    tuples), and the frame's times (CLOCK_MONOTONIC / CLOCK_REALTIME ns)."""

    __slots__ = ("seq", "valid", "filtered", "coasting", "has_motion", "x_m", "y_m", "yaw_rad",
                 "covariance", "vx_mps", "vy_mps", "yaw_rate_radps", "velocity_covariance",
                 "mode", "refusal", "markers", "capture_mono_ns", "capture_real_ns",
                 "publish_mono_ns", "publish_real_ns", "predict_horizon_ms")

    def __init__(self, r):
        self.seq = r.seq
        self.valid = bool(r.flags & _FLAG_VALID)
        self.filtered = bool(r.flags & _FLAG_FILTERED)
        self.coasting = bool(r.flags & _FLAG_COASTING)
        self.has_motion = bool(r.flags & _FLAG_MOTION)
        self.x_m, self.y_m, self.yaw_rad = r.x_m, r.y_m, r.yaw_rad
        self.covariance = tuple(r.covariance)
        self.vx_mps, self.vy_mps, self.yaw_rate_radps = r.vx_mps, r.vy_mps, r.yaw_rate_radps
        self.velocity_covariance = tuple(
            r.state_covariance[(3 + i) * _STATE + 3 + j] for i in range(3) for j in range(3))
        self.mode = _lib.ceilpose_mode_name(r.mode).decode()
        self.refusal = _lib.ceilpose_refusal_name(r.refusal).decode()
        self.markers = r.markers
        self.capture_mono_ns = r.capture_mono_ns
        self.capture_real_ns = r.capture_real_ns
        self.publish_mono_ns = r.publish_mono_ns
        self.publish_real_ns = r.publish_real_ns
        self.predict_horizon_ms = r.predict_horizon_ms

    def age_ms(self, now_mono_ns=None):
        """How old the frame is, milliseconds (now by default)."""
        now = time.monotonic_ns() if now_mono_ns is None else now_mono_ns
        return (now - self.capture_mono_ns) / 1e6

    def __repr__(self):
        if not self.valid:
            return f"Pose(seq={self.seq}, valid=False, refusal={self.refusal!r})"
        return (f"Pose(seq={self.seq}, x_m={self.x_m:.4f}, y_m={self.y_m:.4f}, "
                f"yaw_rad={self.yaw_rad:.4f}, vx_mps={self.vx_mps:.3f}, "
                f"vy_mps={self.vy_mps:.3f}, mode={self.mode!r}, markers={self.markers})")


class FleetPose:
    """Another robot's pose from this robot's fleet segment (SPEC §12).

    timestamp_ns is its mid-exposure instant on THIS robot's CLOCK_MONOTONIC
    (comparable with time.monotonic_ns()); age_ms how old the pose was when
    read (or, predicted, how far it was carried); latency_ms arrival minus
    exposure on the two robots' realtime clocks; stale True once nothing came
    from it for the daemon's fleet.stale_after_ms; predicted True when it was
    carried to the instant asked for."""

    __slots__ = ("robot", "seq", "x_m", "y_m", "yaw_rad", "covariance", "has_motion", "vx_mps",
                 "vy_mps", "yaw_rate_radps", "velocity_covariance", "mode", "markers",
                 "timestamp_ns", "stamp_real_ns", "age_ms", "latency_ms", "stale", "predicted",
                 "samples", "lost")

    def __init__(self, r, now_mono_ns):
        p = r.pose
        self.robot = r.robot.decode(errors="replace")
        self.seq = p.seq
        self.x_m, self.y_m, self.yaw_rad = p.x_m, p.y_m, p.yaw_rad
        self.covariance = tuple(p.covariance)
        self.has_motion = bool(p.flags & _FLAG_MOTION)
        self.vx_mps, self.vy_mps, self.yaw_rate_radps = p.vx_mps, p.vy_mps, p.yaw_rate_radps
        self.velocity_covariance = tuple(
            p.state_covariance[(3 + i) * _STATE + 3 + j] for i in range(3) for j in range(3))
        self.mode = _lib.ceilpose_mode_name(p.mode).decode()
        self.markers = p.markers
        self.timestamp_ns = p.capture_mono_ns
        self.stamp_real_ns = p.capture_real_ns
        self.age_ms = (now_mono_ns - p.capture_mono_ns) / 1e6
        self.latency_ms = r.latency_ns / 1e6
        self.stale = bool(r.fleet_flags & _FLEET_STALE)
        self.predicted = bool(r.fleet_flags & _FLEET_PREDICTED)
        self.samples = r.samples
        self.lost = r.lost

    def __repr__(self):
        return (f"FleetPose(robot={self.robot!r}, x_m={self.x_m:.4f}, y_m={self.y_m:.4f}, "
                f"yaw_rad={self.yaw_rad:.4f}, age_ms={self.age_ms:.1f}, stale={self.stale})")


class Client:
    """A reader of one pose segment. Not for concurrent use from several
    threads (open one Client per thread)."""

    def __init__(self, shm=DEFAULT_SHM):
        self._handle = ctypes.c_void_p()
        self._fleet = ctypes.c_void_p()  # opened by the first fleet()
        if not isinstance(shm, str) or "\x00" in shm:
            # A NUL would cut the name C sees ('/p2s\x00x' would open '/p2s').
            raise ValueError(f"shm must be a segment name without NUL characters, not {shm!r}")
        self._fleet_records = None
        self._record = _PoseRecord()
        self._last_seq = 0
        self.shm = shm
        rc = _lib.ceilpose_client_open(shm.encode(), ctypes.byref(self._handle))
        if rc != 0:
            _raise(rc, f"cannot open the pose segment {shm}")

    def close(self):
        if self._fleet:
            _lib.ceilpose_client_fleet_close(self._fleet)
            self._fleet = ctypes.c_void_p()
        if self._handle:
            _lib.ceilpose_client_close(self._handle)
            self._handle = ctypes.c_void_p()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def _check_open(self):
        if not self._handle:
            raise CeilposeError(-1, f"the client of {self.shm} is closed")

    def latest(self):
        """The latest pose, without waiting (NO_POSE before the first)."""
        self._check_open()
        rc = _lib.ceilpose_client_read_latest(self._handle, ctypes.byref(self._record))
        if rc != 0:
            _raise(rc, f"no latest pose on {self.shm}")
        return self._keep(Pose(self._record))

    def wait_next(self, timeout_s=1.0, after_seq=None):
        """Blocks until a pose newer than after_seq (default: the last one this
        client returned) exists, at most timeout_s seconds (None: forever)."""
        self._check_open()
        after = self._last_seq if after_seq is None else _whole(after_seq, "after_seq", 0,
                                                                 2**64 - 1, "poses")
        if timeout_s is None:
            timeout_ms = -1
        else:
            # Up to 24 days (the C call's int32 milliseconds); None waits forever.
            _whole(timeout_s, "timeout_s", 0, (2**31 - 1) / 1000, "s (None: forever)")
            timeout_ms = min(int(float(timeout_s) * 1000), 2**31 - 1)
        rc = _lib.ceilpose_client_wait_next(self._handle, after, timeout_ms,
                                            ctypes.byref(self._record))
        if rc != 0:
            _raise(rc, f"no new pose on {self.shm} within {timeout_s} s")
        return self._keep(Pose(self._record))

    def predict(self, t_mono_ns=None):
        """The latest pose carried to t_mono_ns (default: now) by the daemon's
        filter: "where am I now". HORIZON beyond the daemon's
        filter.predict_horizon_ms, NO_MOTION without a filtered pose."""
        self._check_open()
        t = time.monotonic_ns() if t_mono_ns is None else _instant(t_mono_ns, "t_mono_ns")
        rc = _lib.ceilpose_client_predict(self._handle, t, ctypes.byref(self._record))
        if rc != 0:
            _raise(rc, f"cannot predict the pose on {self.shm} to {t} ns")
        return Pose(self._record)

    def fleet(self, t_mono_ns=None):
        """Every other robot the daemon keeps in "<shm>-fleet": a dict from
        robot name to FleetPose, each carried to t_mono_ns (CLOCK_MONOTONIC)
        by its own filter's motion when given (FleetPose.predicted says
        whether it could be), else as received. NOT_FOUND when the daemon
        keeps no fleet (fleet.enabled false, or DDS off)."""
        self._check_open()
        t = 0 if t_mono_ns is None else _instant(t_mono_ns, "t_mono_ns")
        if not self._fleet:
            rc = _lib.ceilpose_client_fleet_open(self.shm.encode(), ctypes.byref(self._fleet))
            if rc != 0:
                _raise(rc, f"cannot open the fleet segment of {self.shm}")
            info = _FleetInfo()
            _lib.ceilpose_client_fleet_info(self._fleet, ctypes.byref(info))
            self._fleet_records = (_FleetRecord * info.capacity)()
        count = ctypes.c_uint32()
        rc = _lib.ceilpose_client_fleet_read(self._fleet, t, self._fleet_records,
                                             len(self._fleet_records), ctypes.byref(count))
        if rc != 0:
            _raise(rc, f"cannot read the fleet segment of {self.shm}")
        now = time.monotonic_ns()
        return {p.robot: p for p in (FleetPose(self._fleet_records[i], now)
                                     for i in range(count.value))}

    def fleet_counters(self):
        """The fleet keeper's counters: accepted and refused samples (full,
        future, past, invalid, duplicate), removed robots, capacity."""
        self.fleet()  # opens the segment if needed
        info = _FleetInfo()
        _lib.ceilpose_client_fleet_info(self._fleet, ctypes.byref(info))
        return {name: getattr(info, name) for name, _ in _FleetInfo._fields_
                if not name.startswith("reserved")}

    def _keep(self, pose):
        self._last_seq = pose.seq
        return pose
