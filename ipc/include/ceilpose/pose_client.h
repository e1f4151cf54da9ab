/* ceilpose pose client: read the robot pose that ceilposed publishes in POSIX
 * shared memory (default segment "/ceilpose"), from C or C++.
 *
 *   ceilpose_client* c = NULL;
 *   if (ceilpose_client_open("/ceilpose", &c) != CEILPOSE_OK) {
 *     fprintf(stderr, "%s\n", ceilpose_last_error_message());
 *   }
 *   ceilpose_pose p;
 *   uint64_t seq = 0;
 *   while (ceilpose_client_wait_next(c, seq, 1000, &p) == CEILPOSE_OK) seq = p.seq;
 *   ceilpose_client_close(c);
 *
 * Build with `pkg-config --cflags --libs ceilpose-client`. The records below are
 * the exact bytes of the shared segment (ABI version CEILPOSE_CLIENT_ABI_VERSION);
 * the daemon (C++) includes this header too, so both sides share one layout.
 *
 * Threads: a handle may be used by one thread at a time; distinct handles are
 * independent. No call allocates or blocks except open/reattach (allocate) and
 * wait_next (blocks up to its timeout). docs/ipc.md describes the segment.
 */
#ifndef CEILPOSE_POSE_CLIENT_H
#define CEILPOSE_POSE_CLIENT_H

#include <stddef.h> /* offsetof, for the layout checks below */
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Version of the shared-segment layout and of these records. A reader refuses
 * a segment of another version (CEILPOSE_ERR_ABI_MISMATCH). */
#define CEILPOSE_CLIENT_ABI_VERSION 3
/* Default segment name (SPEC §7: --shm defaults to /ceilpose). */
#define CEILPOSE_DEFAULT_SHM_NAME "/ceilpose"
/* Poses kept in the segment's ring of recent poses. */
#define CEILPOSE_POSE_RING_LENGTH 64
#define CEILPOSE_SOURCE_TEXT_SIZE 96
/* Slots of ceilpose_status.refusals: room for refusal reasons added later. */
#define CEILPOSE_REFUSAL_SLOTS 16

/* ceilpose_pose.flags */
#define CEILPOSE_POSE_VALID 0x1u    /* x_m, y_m, yaw_rad and covariance hold a pose */
#define CEILPOSE_POSE_FILTERED 0x2u /* the temporal filter produced this pose */
#define CEILPOSE_POSE_COASTING 0x4u /* predicted: no marker fix in this frame */
#define CEILPOSE_POSE_MOTION 0x8u   /* velocity, acceleration and state_covariance are set */
/* Entries of ceilpose_pose.state_covariance (9 x 9, row-major). */
#define CEILPOSE_STATE_SIZE 9

/* ceilpose_pose.mode: the positioning method used (SPEC §5 "mode" names). */
enum ceilpose_mode {
  CEILPOSE_MODE_AUTO = 0,        /* "auto" */
  CEILPOSE_MODE_AXES = 1,        /* "axes": change of axes */
  CEILPOSE_MODE_BARYCENTRIC = 2, /* "barycentric" */
  CEILPOSE_MODE_LSQ = 3          /* "lsq": least squares over all markers */
};

/* ceilpose_status.fix_state */
enum ceilpose_fix_state {
  CEILPOSE_FIX_NONE = 0,     /* no pose since start */
  CEILPOSE_FIX_OK = 1,       /* last frame gave a pose */
  CEILPOSE_FIX_COASTING = 2, /* recent fix, current poses predicted */
  CEILPOSE_FIX_LOST = 3      /* no fix for longer than the filter coasts */
};

/* One published pose. Times: *_mono_ns on CLOCK_MONOTONIC, *_real_ns on
 * CLOCK_REALTIME, both in nanoseconds. capture_mono_ns is the middle of the
 * frame's exposure (docs/latency.md): the instant the pose and motion are of. */
typedef struct ceilpose_pose {
  uint64_t seq;            /* 1, 2, 3, ... per writer generation; 0 = none */
  int64_t capture_mono_ns; /* when the camera captured the frame */
  int64_t capture_real_ns;
  int64_t publish_mono_ns; /* when the daemon published the pose */
  int64_t publish_real_ns;
  double x_m; /* robot position in `map`, metres (x East, y North) */
  double y_m;
  double yaw_rad;       /* (-pi, pi], CCW from East */
  double covariance[9]; /* (x_m, y_m, yaw_rad) row-major, SI units squared */
  uint32_t flags;       /* CEILPOSE_POSE_* */
  uint8_t mode;         /* enum ceilpose_mode */
  uint8_t refusal;      /* why the frame gave no measurement: ceilpose_refusal_name(); 0 "none" */
  uint16_t markers;     /* decoded markers used */
  /* ABI 3: the temporal filter's motion at capture_mono_ns, world frame
   * (CEILPOSE_POSE_MOTION; zero without it). ceilpose_client_predict carries
   * the pose to another instant with them. */
  double vx_mps;
  double vy_mps;
  double yaw_rate_radps; /* CCW positive */
  double ax_mps2;
  double ay_mps2;
  double yaw_accel_radps2;
  /* Covariance of the filter's state (x_m, y_m, yaw_rad, vx_mps, vy_mps,
   * yaw_rate_radps, ax_mps2, ay_mps2, yaw_accel_radps2), row-major, SI units
   * squared: the velocity's is rows and columns 3-5; rows 0-2 = covariance. */
  double state_covariance[CEILPOSE_STATE_SIZE * CEILPOSE_STATE_SIZE];
  /* The process noise prediction adds: the jerk's power spectral density of
   * x, y ((m/s^3)^2 s) and yaw ((rad/s^3)^2 s). */
  double jerk_density[3];
  /* ceilpose_client_predict refuses instants further than this from
   * capture_mono_ns (the daemon's filter.predict_horizon_ms). */
  uint32_t predict_horizon_ms;
  uint32_t reserved0;
} ceilpose_pose;

/* Daemon health, what `ceilposectl status` shows. Filled by the daemon about
 * once a second. */
typedef struct ceilpose_status {
  double fps;              /* processed frames per second, recent */
  uint64_t frames;         /* frames captured since start */
  uint64_t drops;          /* frames the capture ring dropped */
  uint64_t skipped;        /* frames the pipeline skipped to stay current */
  uint64_t outages;        /* times the source stopped delivering and recovered */
  uint32_t latency_p50_us; /* capture -> pose published */
  uint32_t latency_p90_us;
  uint32_t latency_p99_us;
  uint32_t latency_max_us;
  uint32_t fix_state; /* enum ceilpose_fix_state */
  /* Frames swept only where the filter predicted the markers (tracking),
   * since the daemon started, modulo 2^32; 0 from daemons before it. */
  uint32_t tracked_frames;
  int64_t updated_mono_ns;                /* when the daemon filled this record */
  char source[CEILPOSE_SOURCE_TEXT_SIZE]; /* NUL-terminated, e.g. "v4l2:/dev/video0" */
  /* Frames per refusal reason since the daemon started: refusals[i] counts
   * the reason ceilpose_refusal_name(i) ("none": frames that gave a pose);
   * the first refusal_count slots are used. */
  uint32_t refusal_count;
  /* Frames swept whole before their pose (no fix, an uncertain prediction,
   * or a failed track swept again), since the daemon started, modulo 2^32;
   * 0 from daemons before it. The scheduled whole sweep runs after its
   * frame's tracked pose, as a check, and is not counted here. */
  uint32_t full_sweep_frames;
  uint64_t refusals[CEILPOSE_REFUSAL_SLOTS];
} ceilpose_status;

/* Writer state in the segment header. */
enum ceilpose_writer_state {
  CEILPOSE_STATE_STARTING = 1, /* segment created, no pose yet */
  CEILPOSE_STATE_RUNNING = 2,  /* at least one pose published */
  CEILPOSE_STATE_STOPPED = 3   /* the daemon stopped cleanly */
};

/* What ceilpose_client_liveness concludes about the writer. */
enum ceilpose_liveness {
  CEILPOSE_LIVE = 0,          /* heartbeat fresh, process alive */
  CEILPOSE_LIVE_STARTING = 1, /* alive, no pose yet */
  CEILPOSE_STOPPED = 2,       /* the writer marked the segment stopped */
  CEILPOSE_STALE = 3,         /* process exists but the heartbeat is too old */
  CEILPOSE_WRITER_DEAD = 4,   /* the writer process is gone (crashed, killed) */
  CEILPOSE_RESTARTED = 5      /* the name now holds a newer writer: reattach */
};

typedef struct ceilpose_writer_info {
  int32_t pid;
  uint32_t state;      /* enum ceilpose_writer_state */
  uint64_t generation; /* random per writer start; changes on restart */
  int64_t start_mono_ns;
  int64_t start_real_ns;
  int64_t heartbeat_mono_ns; /* last sign of life, CLOCK_MONOTONIC */
  uint32_t stale_after_ms;   /* the daemon's ipc.stale_after_ms */
  uint32_t reserved0;
} ceilpose_writer_info;

/* Return codes: 0 success, negative errors. */
enum ceilpose_error {
  CEILPOSE_OK = 0,
  CEILPOSE_ERR_INVALID_ARGUMENT = -1, /* NULL pointer, bad name */
  CEILPOSE_ERR_NOT_FOUND = -2,        /* no segment of that name: daemon not running */
  CEILPOSE_ERR_PERMISSION = -3,       /* not allowed to open the segment (group?) */
  CEILPOSE_ERR_ABI_MISMATCH = -4,     /* segment of another ABI version */
  CEILPOSE_ERR_BAD_SIZE = -5,         /* segment size is not what this ABI expects */
  CEILPOSE_ERR_BAD_MAGIC = -6,        /* not a ceilpose segment */
  CEILPOSE_ERR_NOT_READY = -7,        /* the writer is still initializing it */
  CEILPOSE_ERR_SYSTEM = -8,           /* other system error (see message) */
  CEILPOSE_ERR_NO_MEMORY = -9,
  CEILPOSE_ERR_NO_POSE = -10,     /* nothing published yet */
  CEILPOSE_ERR_BUSY = -11,        /* writer kept overwriting the pose during the read */
  CEILPOSE_ERR_TIMEOUT = -12,     /* no new pose within the timeout */
  CEILPOSE_ERR_STOPPED = -13,     /* the daemon stopped cleanly */
  CEILPOSE_ERR_WRITER_DEAD = -14, /* the writer process is gone */
  CEILPOSE_ERR_LIVE_WRITER = -15, /* (writer side) another daemon owns the name */
  CEILPOSE_ERR_NO_GROUP = -16,    /* (writer side) configured group does not exist */
  CEILPOSE_ERR_NO_MOTION = -17,   /* the latest pose is invalid or carries no motion */
  CEILPOSE_ERR_HORIZON = -18      /* the instant is beyond predict_horizon_ms of the frame */
};

typedef struct ceilpose_client ceilpose_client;

/* Opens the segment `name` (NULL for "/ceilpose") read-only and checks magic,
 * ABI version and size. On success stores a new handle in *out. */
int ceilpose_client_open(const char* name, ceilpose_client** out);

/* Unmaps and frees the handle. NULL is allowed. */
void ceilpose_client_close(ceilpose_client* client);

/* Copies the latest pose into *out without waiting for the writer. Returns
 * CEILPOSE_ERR_NO_POSE before the first pose, CEILPOSE_ERR_BUSY if the pose
 * was overwritten on every retry (the writer never waits for readers). */
int ceilpose_client_read_latest(ceilpose_client* client, ceilpose_pose* out);

/* Blocks (futex, no polling) until a pose with seq > after_seq exists, then
 * copies it (the newest) into *out. timeout_ms < 0 waits forever. Returns
 * CEILPOSE_ERR_TIMEOUT, or CEILPOSE_ERR_STOPPED / CEILPOSE_ERR_WRITER_DEAD
 * when no pose can come from this writer any more. */
int ceilpose_client_wait_next(ceilpose_client* client, uint64_t after_seq, int32_t timeout_ms,
                              ceilpose_pose* out);

/* The latest pose carried to t_mono_ns (CLOCK_MONOTONIC), "where am I now":
 * position, yaw, velocity and their covariance (grown by the process noise)
 * at that instant, by the filter's own constant-acceleration model; the
 * capture_* and publish_* times still name the frame it came from. Lock-free
 * and allocation-free, like read_latest. Returns CEILPOSE_ERR_NO_MOTION when
 * the latest pose is invalid or unfiltered, CEILPOSE_ERR_HORIZON when
 * |t_mono_ns - capture_mono_ns| exceeds its predict_horizon_ms (*out then
 * still holds the latest pose, unpredicted). */
int ceilpose_client_predict(ceilpose_client* client, int64_t t_mono_ns, ceilpose_pose* out);

/* Judges the writer: stopped, dead (pid gone), stale (heartbeat older than
 * stale_after_ms; 0 = the daemon's own ipc.stale_after_ms, published in the
 * segment), restarted (the name now holds another generation) or live. */
int ceilpose_client_liveness(ceilpose_client* client, int64_t stale_after_ms,
                             enum ceilpose_liveness* out);

/* Re-opens the name and, if it holds a valid segment, switches the handle to
 * it (a restarted daemon). On failure the handle keeps the old segment. */
int ceilpose_client_reattach(ceilpose_client* client);

/* Copies the daemon's status record into *out. */
int ceilpose_client_read_status(ceilpose_client* client, ceilpose_status* out);

/* Copies the header's writer identity and heartbeat into *out. */
int ceilpose_client_writer_info(ceilpose_client* client, ceilpose_writer_info* out);

/* Copies up to max_poses of the most recent poses, newest first, into out and
 * stores how many in *count. */
int ceilpose_client_read_recent(ceilpose_client* client, ceilpose_pose* out, uint32_t max_poses,
                                uint32_t* count);

/* Static English text for a return code. */
const char* ceilpose_strerror(int code);

/* Name of a positioning mode (enum ceilpose_mode) as SPEC §5 prints it:
 * "auto", "axes", "barycentric", "lsq"; "unknown" otherwise. */
const char* ceilpose_mode_name(uint8_t mode);

/* snake_case name of refusal reason `index` (SPEC §5 "refusal" of locate):
 * "none", "unusable_frame", "no_markers", ...; "unknown" beyond the last. */
const char* ceilpose_refusal_name(unsigned index);

/* Message of the last call in this thread: what failed, naming the segment,
 * its size and mode where relevant; "" when that call succeeded. Every call
 * sets it, so an older failure never shows after a later call. */
const char* ceilpose_last_error_message(void);

/* ---- The fleet (SPEC §12) ------------------------------------------------
 * ceilposed keeps every other robot's latest pose on its DDS domain in the
 * segment "<shm>-fleet" (e.g. "/ceilpose-fleet"), one seqlocked slot per
 * robot. A controller reads all of them, each carried to one instant:
 *
 *   ceilpose_fleet* f = NULL;
 *   if (ceilpose_client_fleet_open("/ceilpose", &f) != CEILPOSE_OK) ...;
 *   ceilpose_fleet_robot robots[64];
 *   uint32_t n = 0;
 *   ceilpose_client_fleet_read(f, now_mono_ns, robots, 64, &n);
 *
 * Lock-free and allocation-free after open, like ceilpose_client_predict. */

/* Version of the fleet segment's layout; a reader refuses another one
 * (CEILPOSE_ERR_ABI_MISMATCH). Independent of CEILPOSE_CLIENT_ABI_VERSION. */
#define CEILPOSE_FLEET_ABI_VERSION 1
/* Appended to the pose segment's name: "/ceilpose" -> "/ceilpose-fleet". */
#define CEILPOSE_FLEET_SUFFIX "-fleet"
/* Room for a robot name and its NUL (ROS name tokens are shorter). */
#define CEILPOSE_ROBOT_NAME_SIZE 64

/* ceilpose_fleet_robot.fleet_flags */
#define CEILPOSE_FLEET_STALE 0x1u     /* nothing from it for fleet.stale_after_ms, or it left */
#define CEILPOSE_FLEET_PREDICTED 0x2u /* pose carried to the instant asked for */
/* Asked to predict, but it could not be: no motion state, or the instant is
 * beyond its predict_horizon_ms (the pose is then as received). */
#define CEILPOSE_FLEET_NOT_PREDICTED 0x4u

/* One neighbour. pose.capture_mono_ns is its mid-exposure instant on THIS
 * robot's CLOCK_MONOTONIC (its CLOCK_REALTIME stamp minus this robot's
 * realtime-monotonic offset); pose.capture_real_ns is the stamp as sent. */
typedef struct ceilpose_fleet_robot {
  char robot[CEILPOSE_ROBOT_NAME_SIZE]; /* NUL-terminated ROS name */
  ceilpose_pose pose;
  int64_t received_mono_ns; /* when this robot received the sample */
  /* Arrival minus exposure, both CLOCK_REALTIME, ns: transport delay plus the
   * clock offset between the two robots (negative: its clock is ahead). */
  int64_t latency_ns;
  uint64_t samples;     /* samples accepted from it since it appeared */
  uint32_t fleet_flags; /* CEILPOSE_FLEET_* */
  uint32_t lost;        /* samples it sent that never arrived (gaps in pose.seq) */
} ceilpose_fleet_robot;

/* What the keeper of the segment counted; see docs/fleet.md. */
typedef struct ceilpose_fleet_info {
  int32_t pid;         /* the daemon writing the segment */
  uint32_t state;      /* enum ceilpose_writer_state */
  uint64_t generation; /* random per daemon start */
  int64_t heartbeat_mono_ns;
  uint32_t capacity;       /* slots (fleet.capacity) */
  uint32_t robots;         /* slots in use now */
  uint32_t stale_after_ms; /* fleet.stale_after_ms */
  uint32_t reserved0;
  uint64_t accepted;          /* samples written to a slot */
  uint64_t refused_full;      /* samples of robots that found no free slot */
  uint64_t refused_future;    /* stamped further ahead than fleet.max_clock_offset_ms */
  uint64_t refused_past;      /* older than fleet.max_clock_offset_ms + stale_after_ms */
  uint64_t refused_invalid;   /* non-finite or invalid pose, bad name */
  uint64_t refused_duplicate; /* a second writer under a name already held */
  uint64_t removed;           /* robots removed after going stale */
} ceilpose_fleet_info;

typedef struct ceilpose_fleet ceilpose_fleet;

/* Opens "<shm>-fleet" for the pose segment name `shm` (NULL: "/ceilpose"),
 * read-only, and checks magic, CEILPOSE_FLEET_ABI_VERSION and size. */
int ceilpose_client_fleet_open(const char* shm, ceilpose_fleet** out);

/* Unmaps and frees the handle. NULL is allowed. */
void ceilpose_client_fleet_close(ceilpose_fleet* fleet);

/* Copies up to max_robots neighbours into out, in slot order, and stores how
 * many in *count. t_mono_ns != 0: each pose is carried to that instant
 * (CLOCK_MONOTONIC) by the same model and horizon as ceilpose_client_predict,
 * flag CEILPOSE_FLEET_PREDICTED, or CEILPOSE_FLEET_NOT_PREDICTED when it
 * cannot be. t_mono_ns == 0: as received. A slot the writer kept rewriting
 * during the read is skipped (it is read again on the next call). */
int ceilpose_client_fleet_read(ceilpose_fleet* fleet, int64_t t_mono_ns, ceilpose_fleet_robot* out,
                               uint32_t max_robots, uint32_t* count);

/* One neighbour by name, as fleet_read would give it. CEILPOSE_ERR_NO_POSE
 * when no slot holds that robot. */
int ceilpose_client_fleet_find(ceilpose_fleet* fleet, const char* robot, int64_t t_mono_ns,
                               ceilpose_fleet_robot* out);

/* The keeper's identity and counters. */
int ceilpose_client_fleet_info(ceilpose_fleet* fleet, ceilpose_fleet_info* out);

/* Layout checks, so C and C++ compilers agree on the shared bytes. */
#ifdef __cplusplus
#define CEILPOSE_STATIC_ASSERT(c, m) static_assert(c, m)
#else
#define CEILPOSE_STATIC_ASSERT(c, m) _Static_assert(c, m)
#endif
CEILPOSE_STATIC_ASSERT(sizeof(ceilpose_pose) == 872, "ceilpose_pose layout");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, x_m) == 40, "ceilpose_pose.x_m offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, covariance) == 64, "ceilpose_pose.covariance");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, flags) == 136, "ceilpose_pose.flags offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, markers) == 142, "ceilpose_pose.markers offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, vx_mps) == 144, "ceilpose_pose.vx_mps offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, state_covariance) == 192, "state_covariance");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, jerk_density) == 840, "jerk_density offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_pose, predict_horizon_ms) == 864, "horizon offset");
CEILPOSE_STATIC_ASSERT(sizeof(ceilpose_status) == 304, "ceilpose_status layout");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_status, refusals) == 176, "ceilpose_status.refusals");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_status, latency_p50_us) == 40, "status latency offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_status, updated_mono_ns) == 64, "status time offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_status, source) == 72, "ceilpose_status.source");
CEILPOSE_STATIC_ASSERT(sizeof(ceilpose_fleet_robot) == 968, "ceilpose_fleet_robot layout");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_fleet_robot, pose) == 64, "fleet robot pose offset");
CEILPOSE_STATIC_ASSERT(offsetof(ceilpose_fleet_robot, latency_ns) == 944, "fleet latency offset");
CEILPOSE_STATIC_ASSERT(sizeof(ceilpose_fleet_info) == 96, "ceilpose_fleet_info layout");
#undef CEILPOSE_STATIC_ASSERT

#ifdef __cplusplus
}
#endif

#endif /* CEILPOSE_POSE_CLIENT_H */
