/* pose_printer: a minimal controller in C that prints every pose ceilposed
 * publishes, using only the C client (pkg-config ceilpose-client).
 *
 *   ceilpose_pose_printer [--shm NAME] [--count N]
 *
 * It blocks in ceilpose_client_wait_next (no polling), and follows a daemon
 * restart by re-attaching when the liveness check says so. Exit status: 0
 * after N poses, 1 on error, 3 when no daemon is publishing. */
#define _POSIX_C_SOURCE 200809L
#include <ceilpose/pose_client.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { kExitOk = 0, kExitFailure = 1, kExitUsage = 2, kExitNoDaemon = 3 };

/* A restarted daemon may take a moment to create its new segment. */
static const int32_t kWaitTimeoutMs = 1000;
static const int64_t kStaleAfterMs = 1000;
static const double kDegreesPerRadian = 57.29577951308232;

static void sleep_ms(long ms) {
  struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
  while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
  }
}

static int64_t monotonic_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void print_pose(const ceilpose_pose* p) {
  const double age_us = (double)(monotonic_ns() - p->publish_mono_ns) / 1000.0;
  if (p->flags & CEILPOSE_POSE_VALID) {
    printf("seq %8llu  x %8.4f m  y %8.4f m  yaw %7.2f deg  mode %s  markers %2u  age %.0f us\n",
           (unsigned long long)p->seq, p->x_m, p->y_m, p->yaw_rad * kDegreesPerRadian,
           ceilpose_mode_name(p->mode), (unsigned)p->markers, age_us);
  } else {
    printf("seq %8llu  no fix\n", (unsigned long long)p->seq);
  }
  fflush(stdout);
}

int main(int argc, char** argv) {
  const char* name = CEILPOSE_DEFAULT_SHM_NAME;
  long count = -1;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--shm") == 0 && i + 1 < argc) {
      name = argv[++i];
    } else if (strcmp(argv[i], "--count") == 0 && i + 1 < argc) {
      count = strtol(argv[++i], NULL, 10);
    } else {
      fprintf(stderr, "usage: %s [--shm NAME] [--count N]\n", argv[0]);
      return strcmp(argv[i], "--help") == 0 ? kExitOk : kExitUsage;
    }
  }

  ceilpose_client* client = NULL;
  int rc = ceilpose_client_open(name, &client);
  if (rc != CEILPOSE_OK) {
    fprintf(stderr, "pose_printer: %s: %s\n", ceilpose_strerror(rc), ceilpose_last_error_message());
    return rc == CEILPOSE_ERR_NOT_FOUND ? kExitNoDaemon : kExitFailure;
  }

  uint64_t last_seq = 0;
  long printed = 0;
  int status = kExitOk;
  while (count < 0 || printed < count) {
    ceilpose_pose pose;
    rc = ceilpose_client_wait_next(client, last_seq, kWaitTimeoutMs, &pose);
    if (rc == CEILPOSE_OK) {
      print_pose(&pose);
      last_seq = pose.seq;
      ++printed;
      continue;
    }
    if (rc == CEILPOSE_ERR_BUSY) continue;
    /* Timeout, stopped or dead: a new daemon may have taken the name over. */
    enum ceilpose_liveness liveness;
    ceilpose_client_liveness(client, kStaleAfterMs, &liveness);
    if (liveness == CEILPOSE_RESTARTED) {
      if (ceilpose_client_reattach(client) == CEILPOSE_OK) {
        fprintf(stderr, "pose_printer: daemon restarted, re-attached to %s\n", name);
        last_seq = 0;
      } else {
        sleep_ms(100); /* its segment is being initialized */
      }
    } else if (rc == CEILPOSE_ERR_STOPPED || rc == CEILPOSE_ERR_WRITER_DEAD) {
      fprintf(stderr, "pose_printer: %s; waiting for a new daemon on %s\n", ceilpose_strerror(rc),
              name);
      sleep_ms(200);
    } else if (rc != CEILPOSE_ERR_TIMEOUT) {
      fprintf(stderr, "pose_printer: %s\n", ceilpose_strerror(rc));
      status = kExitFailure;
      break;
    }
  }
  ceilpose_client_close(client);
  return status;
}
