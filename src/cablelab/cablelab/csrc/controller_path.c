/* The pd_feedforward node's compiled state -> command path (cablelab.plants.cdpr.controller_path
 * loads it with ctypes; the Python law stays the oracle and the fallback).
 *
 * Python plans the law's reference terms ahead (LiveController.plan: per stamp the PD part
 * pd = kp q_d + kd q_d', the four feedforward tension terms b_0..b_3 of 001 eq. 14 and the
 * friction compensation) and puts them here as rows keyed by stamp; each estimate sets the weights
 * c = (1, m, m x_G, m y_G) of the live estimate and its stamp (LiveController.estimate_weights),
 * so a new estimate changes no row. A thread waits on the joint states (a keep-last-1
 * subscription of the node's own rcl node, so one DDS participant per process), takes the newest,
 * finds the row of its stamp and publishes what LiveController.planned_law gives, with the same
 * operations in the same order (the same doubles up to the order of the four-term sum):
 *     c = the live weights if t - t_est <= estimate_timeout, else (1, m_nominal, 0, 0)
 *     ff = k max(c . b, t_min);  tau = pd - kp q;  tau -= kd q';  tau += ff;
 *     tau = max(tau, k t_min);  tau += friction;  tau = min(max(tau, -max_torque), max_torque)
 * (k = r/R) as a Float64MultiArray labelled "<label> stamp=<t>" (the state it answers). No physics
 * here: only that arithmetic on planned rows.
 *
 * References (cp_follow_references, once they come far ahead of the states): the thread also takes
 * the reference samples, after each command and when its wait times out, and keeps each one's
 * stamp, position, orientation, velocity and acceleration (first point, first joint, as
 * cablelab.ros.convert.multidof_arrays reads them) in a ring that Python reads in blocks
 * (cp_references) to plan their rows: no Python wake-up, take or decode per sample.
 *
 * A state this path cannot answer goes to Python whole (cp_handoff, the newest one kept): a bad
 * state (NaN, inf, wrong length: Python's checks report it on /diagnostics) or a stamp without a
 * row (the reference of that stamp not planned: Python commands or holds as it does without this
 * path). A state newer than every row waits up to row_wait s for Python to plan its row first.
 *
 * The thread never waits for Python: Python's thread may run in SCHED_IDLE (python_idle), and a
 * lock it held while preempted would hold the state -> command path up behind every other task
 * on the CPU (a priority inversion). So nothing is shared under a lock. Rows and the estimate are
 * written by Python under a seqlock each (the row's own sequence number; the estimate in a ring
 * of slots, so the thread reads the last complete one while Python writes the next); the thread
 * copies what it reads and checks that the sequence did not move, and a row Python is rewriting
 * at that instant counts as not there (the state goes to Python). The hand-off, the latencies and
 * the reference samples go the other way in single-writer rings, the counters as atomics, and a
 * state waiting for its row sleeps on a futex that each put wakes. Python's own callers are
 * serialised by a mutex the thread never takes. */
#define _GNU_SOURCE
#pragma STDC FP_CONTRACT OFF
#include <limits.h>
#include <linux/futex.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <rcl/error_handling.h>
#include <rcl/rcl.h>
#include <rmw/qos_profiles.h>
#include <rosidl_runtime_c/primitives_sequence_functions.h>
#include <rosidl_runtime_c/string_functions.h>
#include <sensor_msgs/msg/joint_state.h>
#include <std_msgs/msg/float64_multi_array.h>
#include <std_msgs/msg/multi_array_dimension.h>
#include <trajectory_msgs/msg/multi_dof_joint_trajectory.h>
#include "rt_common.h"

#define CP_MAXN 64     /* winches */
#define CP_ROWS 1024   /* rows kept: a second of a 1 kHz reference */
#define CP_HANDOFF 256 /* values of a handed-off state kept (longer ones: the length is kept) */
#define CP_LAT 4096    /* latency samples kept until Python takes them */
#define STAMP_TOL 1e-9
#define CP_REFS 2048   /* reference samples kept until Python reads them (2 s at 1 kHz) */
#define CP_REF_COLS 15 /* t, has position, position (3), quaternion x y z w, velocity (3), acceleration (3) */
#define SLOW_PUBLISH 2e-4 /* s: a command publish longer than this is counted (a fifth of a 1 kHz period) */
#define SLOTS 4        /* estimate and hand-off slots: a reader's copy fails only if 4 writes overtake it */
#define READ_TRIES 8   /* copies of a row or slot tried before it counts as being written */

enum { CP_OK = 0, CP_NO_ROW = 1, CP_BAD_STATE = 2 };

/* ---------------------------------------------------------------- single-writer primitives */
typedef unsigned long seq_t;
#define LOAD(x) __atomic_load_n(&(x), __ATOMIC_RELAXED)
#define STORE(x, v) __atomic_store_n(&(x), (v), __ATOMIC_RELAXED)
#define BUMP(x) STORE(x, LOAD(x) + 1)                 /* one writer: no read-modify-write needed */
#define ACQUIRE(x) __atomic_load_n(&(x), __ATOMIC_ACQUIRE)
#define RELEASE(x, v) __atomic_store_n(&(x), (v), __ATOMIC_RELEASE)
static inline double load_d(const double *x) { double v; __atomic_load(x, &v, __ATOMIC_RELAXED); return v; }
static inline void store_d(double *x, double v) { __atomic_store(x, &v, __ATOMIC_RELAXED); }

/* seqlock (the writer: begin, write, end; a reader: s = read_begin, copy, read_ok(s)) */
static inline void write_begin(seq_t *s) {
  STORE(*s, LOAD(*s) + 1);                           /* odd: being written */
  __atomic_thread_fence(__ATOMIC_RELEASE);
}
static inline void write_end(seq_t *s) { RELEASE(*s, LOAD(*s) + 1); }
static inline seq_t read_begin(const seq_t *s) { return ACQUIRE(*s); }
static inline int read_ok(const seq_t *s, seq_t s1) {
  __atomic_thread_fence(__ATOMIC_ACQUIRE);
  return !(s1 & 1) && LOAD(*s) == s1;
}

static long futex(int *word, int op, int val, const struct timespec *timeout) {
  return syscall(SYS_futex, word, op, val, timeout, NULL, 0);
}

/* ------------------------------------------------------------------------------- the state */
typedef struct {
  seq_t seq;
  double t;
  double pd[CP_MAXN], ff[4][CP_MAXN], fric[CP_MAXN];
} Row;

typedef struct {
  seq_t seq;
  double t, c[4];
} Estimate;

typedef struct {
  seq_t seq;
  double t, wall;
  int nq, nqd;
  double q[CP_HANDOFF], qd[CP_HANDOFF];
} Handoff;

typedef struct {
  int n, has_ff;
  double kp, kd, k, t_min, max_torque, row_wait, estimate_timeout, nominal_c[4];
  pthread_mutex_t py;   /* serialises Python's callers; the thread never takes it */
  /* written by Python, read by the thread */
  Row *rows;
  seq_t nrows;          /* rows ever appended; the newest is rows[(nrows - 1) % CP_ROWS] */
  int rows_put;         /* futex word: bumped by every put */
  Estimate est[SLOTS];
  seq_t nest;           /* estimates ever set; the live one is est[(nest - 1) % SLOTS] */
  int refs_on;
  /* written by the thread, read by Python (nhand, nlat, nrefs: how many the thread wrote) */
  Handoff hand[SLOTS];  /* the states this path did not answer; Python takes the newest */
  seq_t nhand;
  long commanded, waited, publish_failed, taken, wakes;
  long publish_slow;    /* rcl_publish calls that took longer than SLOW_PUBLISH */
  double publish_max;   /* s, the longest rcl_publish */
  double last_commanded_t, last_commanded_wall, last_taken_t;
  double lat[CP_LAT];
  seq_t nlat;
  double refs[CP_REFS][CP_REF_COLS];
  seq_t nrefs;
  /* Python's alone (under py): how far it read each of those, and the reference samples it lost */
  seq_t hand_seen, lat_read, refs_read, refs_lost;
  /* the thread and its rcl entities (on the caller's node) */
  pthread_t thread;
  int running;
  int stop;
  char label[64], error[256];
  rcl_node_t *node;
  rcl_context_t *context;
  rcl_subscription_t sub, ref_sub;
  rcl_publisher_t pub;
  rcl_wait_set_t ws;
  sensor_msgs__msg__JointState js;
  std_msgs__msg__Float64MultiArray cmd;
  trajectory_msgs__msg__MultiDOFJointTrajectory traj;
} cp_t;

/* n winches, PDFF (has_ff) or PD, gains kp kd, k = r/R (m), minimum tension t_min (N), torque
 * limit (N m), row_wait (s), the nominal mass (kg) and how long an estimate stays fresh (s) */
cp_t *cp_create(int n, int has_ff, double kp, double kd, double k, double t_min, double max_torque, double row_wait,
                double nominal_mass, double estimate_timeout) {
  if (n <= 0 || n > CP_MAXN) return NULL;
  cp_t *h = calloc(1, sizeof(cp_t));
  if (!h) return NULL;
  h->rows = calloc(CP_ROWS, sizeof(Row));
  if (!h->rows) { free(h); return NULL; }
  h->n = n; h->has_ff = has_ff; h->kp = kp; h->kd = kd; h->k = k; h->t_min = t_min;
  h->max_torque = max_torque; h->row_wait = row_wait; h->estimate_timeout = estimate_timeout;
  h->nominal_c[0] = 1.0; h->nominal_c[1] = nominal_mass;
  h->last_commanded_t = NAN; h->last_commanded_wall = NAN; h->last_taken_t = NAN;
  pthread_mutex_init(&h->py, NULL);
  return h;
}

/* ---------------------------------------------------------------------------------- rows */
/* (Python, the only writer) the row of stamp t, or NULL */
static Row *own_row(cp_t *h, double t) {
  seq_t lo = h->nrows > CP_ROWS ? h->nrows - CP_ROWS : 0;
  for (seq_t i = h->nrows; i-- > lo;) {
    Row *r = &h->rows[i % CP_ROWS];
    if (fabs(r->t - t) <= STAMP_TOL) return r;
    if (r->t < t - STAMP_TOL) break; /* rows are in stamp order */
  }
  return NULL;
}

/* the newest row's stamp (-inf: none); only a replacement of that same stamp writes it */
static double newest_row_t(const cp_t *h) {
  seq_t n = ACQUIRE(h->nrows);
  return n ? load_d(&h->rows[(n - 1) % CP_ROWS].t) : -INFINITY;
}

/* (any reader) a consistent copy of the first n values of each term of the row of stamp t into
 * out: 1, or 0 if no row has that stamp or it was being rewritten through every try */
static int read_row(const cp_t *h, double t, Row *out) {
  int n = h->n;
  for (int attempt = 0; attempt < READ_TRIES; attempt++) {
    seq_t nr = ACQUIRE(h->nrows), lo = nr > CP_ROWS ? nr - CP_ROWS : 0;
    int busy = 0;
    for (seq_t i = nr; i-- > lo;) {
      const Row *r = &h->rows[i % CP_ROWS];
      seq_t s = read_begin(&r->seq);
      double rt = load_d(&r->t);
      if (fabs(rt - t) <= STAMP_TOL) {
        memcpy(out->pd, r->pd, sizeof(double) * n);
        for (int k = 0; k < 4; k++) memcpy(out->ff[k], r->ff[k], sizeof(double) * n);
        memcpy(out->fric, r->fric, sizeof(double) * n);
        if (read_ok(&r->seq, s)) { out->t = rt; return 1; }
        busy = 1;
        break;
      }
      if (!read_ok(&r->seq, s)) { busy = 1; continue; }  /* its stamp read while it changed */
      if (rt < t - STAMP_TOL) break;                     /* rows are in stamp order */
    }
    if (!busy) return 0;
  }
  return 0;
}

/* Put `count` rows (stamps t (count,), pd and fric (count, n), ff (count, 4, n) the tension terms
 * (NULL for PD), row-major): a stamp already kept is replaced, a newer one appended; an older stamp
 * that is not kept is ignored. Returns how many were kept. */
int cp_put_rows(cp_t *h, int count, const double *t, const double *pd, const double *ff, const double *fric) {
  int n = h->n, kept = 0;
  pthread_mutex_lock(&h->py);
  for (int k = 0; k < count; k++) {
    if (!isfinite(t[k])) continue;
    seq_t nr = h->nrows;
    int append = !nr || t[k] > h->rows[(nr - 1) % CP_ROWS].t + STAMP_TOL;
    Row *r = append ? &h->rows[nr % CP_ROWS] : own_row(h, t[k]);
    if (!r) continue;
    write_begin(&r->seq);
    store_d(&r->t, t[k]);
    memcpy(r->pd, pd + (size_t)k * n, sizeof(double) * n);
    for (int i = 0; i < 4; i++) {
      if (ff) memcpy(r->ff[i], ff + ((size_t)k * 4 + i) * n, sizeof(double) * n);
      else memset(r->ff[i], 0, sizeof(double) * n);
    }
    memcpy(r->fric, fric + (size_t)k * n, sizeof(double) * n);
    write_end(&r->seq);
    if (append) RELEASE(h->nrows, nr + 1);
    kept++;
  }
  if (kept) {
    RELEASE(h->rows_put, LOAD(h->rows_put) + 1);
    futex(&h->rows_put, FUTEX_WAKE_PRIVATE, INT_MAX, NULL);
  }
  pthread_mutex_unlock(&h->py);
  return kept;
}

static int good_state(const cp_t *h, double t, const double *q, int nq, const double *qd, int nqd) {
  if (!isfinite(t) || nq != h->n || nqd != h->n) return 0;
  for (int j = 0; j < nq; j++)
    if (!isfinite(q[j]) || !isfinite(qd[j])) return 0;
  return 1;
}

/* ------------------------------------------------------------------------------ estimate */
/* The live estimate: its stamp t_est and weights c = (1, m, m x_G, m y_G). A row of a stamp more
 * than estimate_timeout after t_est (or t_est NaN: no estimate) takes the nominal mass's
 * (1, m_nominal, 0, 0). */
void cp_set_estimate(cp_t *h, double t_est, double c0, double c1, double c2, double c3) {
  pthread_mutex_lock(&h->py);
  seq_t k = h->nest;
  Estimate *e = &h->est[k % SLOTS];
  write_begin(&e->seq);
  e->t = t_est; e->c[0] = c0; e->c[1] = c1; e->c[2] = c2; e->c[3] = c3;
  write_end(&e->seq);
  RELEASE(h->nest, k + 1);
  pthread_mutex_unlock(&h->py);
}

/* the live estimate's stamp (NaN: none) and weights */
static double read_estimate(const cp_t *h, double c[4]) {
  for (int attempt = 0; attempt < READ_TRIES; attempt++) {
    seq_t k = ACQUIRE(h->nest);
    if (!k) break;
    const Estimate *e = &h->est[(k - 1) % SLOTS];
    seq_t s = read_begin(&e->seq);
    double t = e->t;
    memcpy(c, e->c, sizeof(double) * 4);
    if (read_ok(&e->seq, s)) return t;
  }
  return NAN;
}

/* ----------------------------------------------------------------------------------- law */
static int law(const cp_t *h, double t, const double *q, const double *qd, double *out) {
  Row r;
  if (!read_row(h, t, &r)) return CP_NO_ROW;
  double live[4];
  double t_est = read_estimate(h, live);
  const double *c = isfinite(t_est) && t - t_est <= h->estimate_timeout ? live : h->nominal_c;
  double floor_ = h->k * h->t_min;
  for (int j = 0; j < h->n; j++) {
    double tau = r.pd[j] - h->kp * q[j];
    tau -= h->kd * qd[j];
    if (h->has_ff) {
      double ff = c[0] * r.ff[0][j] + c[1] * r.ff[1][j] + c[2] * r.ff[2][j] + c[3] * r.ff[3][j];
      ff = ff > h->t_min ? ff : h->t_min;
      tau += ff * h->k;
    }
    tau = tau > floor_ ? tau : floor_;
    tau += r.fric[j];
    tau = tau > -h->max_torque ? tau : -h->max_torque;
    out[j] = tau < h->max_torque ? tau : h->max_torque;
  }
  return CP_OK;
}

/* The torques (n,) for the motor state (q (nq,), q' (nqd,)) of stamp t: CP_OK, CP_NO_ROW (no row
 * of that stamp) or CP_BAD_STATE (not finite, wrong length); out untouched unless CP_OK. */
int cp_law(cp_t *h, double t, const double *q, int nq, const double *qd, int nqd, double *out) {
  if (!good_state(h, t, q, nq, qd, nqd)) return CP_BAD_STATE;
  return law(h, t, q, qd, out);
}

/* ----------------------------------------------------------------- thread -> Python */
/* The newest handed-off state, if one came since the last call: 1 and its stamp, wall time of
 * arrival (CLOCK_MONOTONIC, as Python's time.monotonic), lengths and up to cap values each. */
int cp_handoff(cp_t *h, double *t, double *wall, double *q, int *nq, double *qd, int *nqd, int cap) {
  pthread_mutex_lock(&h->py);
  int ready = 0;
  for (;;) {    /* (a copy fails only when the thread wrote SLOTS more meanwhile: then take the newer) */
    seq_t k = ACQUIRE(h->nhand);
    if (k == h->hand_seen) break;
    const Handoff *o = &h->hand[(k - 1) % SLOTS];
    seq_t s = read_begin(&o->seq);
    *t = o->t; *wall = o->wall; *nq = o->nq; *nqd = o->nqd;
    int a = o->nq < cap ? o->nq : cap, b = o->nqd < cap ? o->nqd : cap;
    if (a > CP_HANDOFF) a = CP_HANDOFF;
    if (b > CP_HANDOFF) b = CP_HANDOFF;
    memcpy(q, o->q, sizeof(double) * (a > 0 ? a : 0));
    memcpy(qd, o->qd, sizeof(double) * (b > 0 ? b : 0));
    if (read_ok(&o->seq, s)) {
      h->hand_seen = k;
      ready = 1;
      break;
    }
  }
  pthread_mutex_unlock(&h->py);
  return ready;
}

/* (the thread) hand a state to Python */
static void hand_off(cp_t *h, double t, double wall, const double *q, int nq, const double *qd, int nqd) {
  seq_t k = h->nhand;
  Handoff *o = &h->hand[k % SLOTS];
  write_begin(&o->seq);
  o->t = t; o->wall = wall; o->nq = nq; o->nqd = nqd;
  memcpy(o->q, q, sizeof(double) * (nq < CP_HANDOFF ? nq : CP_HANDOFF));
  memcpy(o->qd, qd, sizeof(double) * (nqd < CP_HANDOFF ? nqd : CP_HANDOFF));
  write_end(&o->seq);
  RELEASE(h->nhand, k + 1);
}

/* Rows of a single-writer ring (size rows of cols doubles, *written ever written) that Python had
 * not read (*read), oldest first, at most cap, into out; rows the writer overwrote before they were
 * read are skipped and counted in *lost (if not NULL). Returns how many. */
static long ring_read(const double *ring, long cols, seq_t size, const seq_t *written, seq_t *read, double *out,
                      long cap, seq_t *lost) {
  seq_t w = ACQUIRE(*written), r = *read;
  if (w - r > size) {
    if (lost) *lost += w - size - r;
    r = w - size;
  }
  seq_t n = w - r < (seq_t)cap ? w - r : (seq_t)cap;
  for (seq_t i = 0; i < n; i++) memcpy(out + i * cols, ring + ((r + i) % size) * cols, sizeof(double) * cols);
  __atomic_thread_fence(__ATOMIC_ACQUIRE);
  /* overwritten meanwhile: the rows before w2 - size, and row w2 - size if the writer is writing row w2 */
  seq_t w2 = LOAD(*written) + 1, gone = w2 > size && w2 - size > r ? w2 - size - r : 0;
  if (gone > n) gone = n;
  if (gone) {
    memmove(out, out + gone * cols, sizeof(double) * cols * (n - gone));
    if (lost) *lost += gone;
  }
  *read = r + n;
  return (long)(n - gone);
}

/* (the thread) append a row to a single-writer ring */
static void ring_write(double *ring, long cols, seq_t size, seq_t *written, const double *row) {
  seq_t w = *written;
  memcpy(ring + (w % size) * cols, row, sizeof(double) * cols);
  RELEASE(*written, w + 1);
}

/* out[0..13]: commanded, handed off, waited for a row, publish failures, running (1/0, -1 failed),
 * stamp and wall time of the last command, states taken, wake-ups of the thread, stamp of the
 * last state taken, command publishes over SLOW_PUBLISH, the longest publish (s), reference samples
 * taken, reference samples lost (not read by Python before the ring wrapped) */
void cp_stats(cp_t *h, double *out) {
  pthread_mutex_lock(&h->py);
  out[0] = ACQUIRE(h->commanded);   /* (the last command's stamp and time are stored before it) */
  out[1] = LOAD(h->nhand); out[2] = LOAD(h->waited); out[3] = LOAD(h->publish_failed);
  out[4] = h->running; out[5] = load_d(&h->last_commanded_t); out[6] = load_d(&h->last_commanded_wall);
  out[7] = LOAD(h->taken); out[8] = LOAD(h->wakes); out[9] = load_d(&h->last_taken_t);
  out[10] = LOAD(h->publish_slow); out[11] = load_d(&h->publish_max);
  seq_t nrefs = ACQUIRE(h->nrefs);
  out[12] = nrefs;
  out[13] = h->refs_lost + (nrefs - h->refs_read > CP_REFS ? nrefs - h->refs_read - CP_REFS : 0);
  pthread_mutex_unlock(&h->py);
}

/* The take -> published times (s) since the last call, at most cap (the newest). */
int cp_latencies(cp_t *h, double *out, int cap) {
  pthread_mutex_lock(&h->py);
  seq_t w = ACQUIRE(h->nlat);
  if (w - h->lat_read > (seq_t)cap) h->lat_read = w - cap;
  long n = ring_read(h->lat, 1, CP_LAT, &h->nlat, &h->lat_read, out, cap, NULL);
  pthread_mutex_unlock(&h->py);
  return (int)n;
}

const char *cp_error(cp_t *h) { return h->error; }

#define TRY(x, what)                                                         \
  do {                                                                       \
    if ((x) != RCL_RET_OK) {                                                 \
      snprintf(h->error, sizeof h->error, "%s: %s", what, rcl_get_error_string().str); \
      rcl_reset_error();                                                     \
      goto fail;                                                             \
    }                                                                        \
  } while (0)

/* The reference samples queued on ref_sub (once cp_follow_references turned it on), into the ring. */
static void take_references(cp_t *h) {
  if (!ACQUIRE(h->refs_on)) return;
  rmw_message_info_t info;
  while (rcl_take(&h->ref_sub, &h->traj, &info, NULL) == RCL_RET_OK) {
    const trajectory_msgs__msg__MultiDOFJointTrajectory *m = &h->traj;
    double row[CP_REF_COLS];
    for (int i = 0; i < CP_REF_COLS; i++) row[i] = NAN;
    row[0] = m->header.stamp.sec + m->header.stamp.nanosec * 1e-9;
    row[1] = 0.0;
    if (m->points.size > 0 && m->points.data[0].transforms.size > 0) {
      const trajectory_msgs__msg__MultiDOFJointTrajectoryPoint *pt = &m->points.data[0];
      const geometry_msgs__msg__Transform *tf = &pt->transforms.data[0];
      row[1] = 1.0;
      row[2] = tf->translation.x; row[3] = tf->translation.y; row[4] = tf->translation.z;
      row[5] = tf->rotation.x; row[6] = tf->rotation.y; row[7] = tf->rotation.z; row[8] = tf->rotation.w;
      if (pt->velocities.size > 0) {
        row[9] = pt->velocities.data[0].linear.x; row[10] = pt->velocities.data[0].linear.y;
        row[11] = pt->velocities.data[0].linear.z;
      }
      if (pt->accelerations.size > 0) {
        row[12] = pt->accelerations.data[0].linear.x; row[13] = pt->accelerations.data[0].linear.y;
        row[14] = pt->accelerations.data[0].linear.z;
      }
    }
    ring_write(&h->refs[0][0], CP_REF_COLS, CP_REFS, &h->nrefs, row);  /* (2 s unread: the oldest is lost) */
  }
  rcl_reset_error();
}

/* The reference samples taken since the last call, oldest first, at most cap rows of
 * CP_REF_COLS doubles (t, has position (1/0), position x y z, quaternion x y z w, linear velocity,
 * linear acceleration; NaN where the message has none); returns how many. */
int cp_references(cp_t *h, double *out, int cap) {
  pthread_mutex_lock(&h->py);
  long n = ring_read(&h->refs[0][0], CP_REF_COLS, CP_REFS, &h->nrefs, &h->refs_read, out, cap, &h->refs_lost);
  pthread_mutex_unlock(&h->py);
  return (int)n;
}

/* (the thread) wait until a put changes rows_put from seen or `left` s passed */
static void wait_for_rows(cp_t *h, int seen, double left) {
  struct timespec ts;
  ts.tv_sec = (time_t)left;
  ts.tv_nsec = (long)((left - (double)ts.tv_sec) * 1e9);
  futex(&h->rows_put, FUTEX_WAIT_PRIVATE, seen, &ts);
}

static void *run(void *arg) {
  cp_t *h = arg;
  double tau[CP_MAXN];
  char label[128];
  while (!ACQUIRE(h->stop)) {
    if (rcl_wait_set_clear(&h->ws) != RCL_RET_OK || rcl_wait_set_add_subscription(&h->ws, &h->sub, NULL) != RCL_RET_OK) {
      rcl_reset_error();
      break;
    }
    rcl_ret_t rc = rcl_wait(&h->ws, RCL_MS_TO_NS(20));
    BUMP(h->wakes);
    if (rc == RCL_RET_TIMEOUT) {
      take_references(h);
      continue;
    }
    if (rc != RCL_RET_OK) {
      rcl_reset_error();
      if (!rcl_context_is_valid(h->context)) break; /* rclpy shut down: nothing more will come */
      struct timespec ts = {0, 1000000};
      nanosleep(&ts, NULL);
      continue;
    }
    rmw_message_info_t info;
    int got = 0;
    while (rcl_take(&h->sub, &h->js, &info, NULL) == RCL_RET_OK) got = 1;
    if (!got) continue;
    double wall = now_s();
    const sensor_msgs__msg__JointState *js = &h->js;
    double t = js->header.stamp.sec + js->header.stamp.nanosec * 1e-9;
    const double *q = js->position.data, *qd = js->velocity.data;
    int nq = (int)js->position.size, nqd = (int)js->velocity.size;
    int res = CP_BAD_STATE;
    BUMP(h->taken);
    if (isfinite(t)) store_d(&h->last_taken_t, t);
    if (good_state(h, t, q, nq, qd, nqd)) {
      int seen = ACQUIRE(h->rows_put);
      res = law(h, t, q, qd, tau);
      if (res == CP_NO_ROW && t > newest_row_t(h) + STAMP_TOL && h->row_wait > 0) {
        /* the reference of this stamp not planned yet: wait for Python to put its row */
        BUMP(h->waited);
        double until = wall + h->row_wait, left;
        while (!ACQUIRE(h->stop) && (left = until - now_s()) > 0) {
          wait_for_rows(h, seen, left);
          seen = ACQUIRE(h->rows_put);
          if ((res = law(h, t, q, qd, tau)) == CP_OK || !(t > newest_row_t(h) + STAMP_TOL)) break;
        }
      }
    }
    if (res != CP_OK) {
      hand_off(h, t, wall, q, nq, qd, nqd);
      continue;
    }
    memcpy(h->cmd.data.data, tau, sizeof(double) * h->n);
    snprintf(label, sizeof label, "%s stamp=%.9f", h->label, t);
    rosidl_runtime_c__String__assign(&h->cmd.layout.dim.data[0].label, label);
    double sent_at = now_s();
    int ok = rcl_publish(&h->pub, &h->cmd, NULL) == RCL_RET_OK;
    if (!ok) rcl_reset_error();
    double done_at = now_s();
    if (done_at - sent_at > SLOW_PUBLISH) BUMP(h->publish_slow);
    if (done_at - sent_at > h->publish_max) store_d(&h->publish_max, done_at - sent_at);
    if (ok) {
      store_d(&h->last_commanded_t, t);
      store_d(&h->last_commanded_wall, done_at);
      RELEASE(h->commanded, h->commanded + 1);
      double lat = done_at - wall;
      ring_write(h->lat, 1, CP_LAT, &h->nlat, &lat);
    } else {
      BUMP(h->publish_failed);
    }
    take_references(h);     /* after the command: off the state -> command path */
  }
  return NULL;
}

static void entities_fini(cp_t *h) {
  if (!h->node) return;
  (void)!rcl_wait_set_fini(&h->ws);
  (void)!rcl_subscription_fini(&h->sub, h->node);
  if (h->refs_on) (void)!rcl_subscription_fini(&h->ref_sub, h->node);
  RELEASE(h->refs_on, 0);
  (void)!rcl_publisher_fini(&h->pub, h->node);
  rcl_reset_error();
  sensor_msgs__msg__JointState__fini(&h->js);
  std_msgs__msg__Float64MultiArray__fini(&h->cmd);
  trajectory_msgs__msg__MultiDOFJointTrajectory__fini(&h->traj);
  h->node = NULL;
}

/* Start the thread on the caller's rcl node and context (rclpy's: Node.handle.pointer,
 * Context.handle.pointer; one DDS participant for the process): a subscription to the joint
 * states of state_topic (reliable, keep-last 1) and a publisher of the commands on command_topic
 * (reliable, transient local, keep-last cmd_depth) labelled "<label> stamp=<t>", made here in the
 * calling thread; the thread only waits, takes and publishes. Returns 0, or -1 (cp_error says
 * why). cp_stop (or cp_destroy) before the node is destroyed. */
int cp_start(cp_t *h, void *node, void *context, const char *state_topic, const char *command_topic, int cmd_depth,
             const char *label) {
  if (h->thread) return 0;
  snprintf(h->label, sizeof h->label, "%s", label);
  h->node = node;
  h->context = context;
  h->sub = rcl_get_zero_initialized_subscription();
  h->pub = rcl_get_zero_initialized_publisher();
  h->ws = rcl_get_zero_initialized_wait_set();
  sensor_msgs__msg__JointState__init(&h->js);
  std_msgs__msg__Float64MultiArray__init(&h->cmd);
  trajectory_msgs__msg__MultiDOFJointTrajectory__init(&h->traj);
  std_msgs__msg__MultiArrayDimension__Sequence__init(&h->cmd.layout.dim, 1);
  h->cmd.layout.dim.data[0].size = h->n;
  h->cmd.layout.dim.data[0].stride = h->n;
  rosidl_runtime_c__double__Sequence__init(&h->cmd.data, h->n);
  rcl_subscription_options_t so = rcl_subscription_get_default_options();
  so.qos = qos(1, 0);
  TRY(rcl_subscription_init(&h->sub, h->node, ROSIDL_GET_MSG_TYPE_SUPPORT(sensor_msgs, msg, JointState),
                            state_topic, &so), "subscribing to the joint states");
  rcl_publisher_options_t po = rcl_publisher_get_default_options();
  po.qos = qos(cmd_depth, 1);
  TRY(rcl_publisher_init(&h->pub, h->node, ROSIDL_GET_MSG_TYPE_SUPPORT(std_msgs, msg, Float64MultiArray),
                         command_topic, &po), "advertising the commands");
  TRY(rcl_wait_set_init(&h->ws, 1, 0, 0, 0, 0, 0, (rcl_context_t *)context, rcl_get_default_allocator()),
      "rcl_wait_set_init");
  RELEASE(h->stop, 0);
  if (pthread_create(&h->thread, NULL, run, h) != 0) {
    snprintf(h->error, sizeof h->error, "pthread_create failed");
    h->thread = 0;
    goto fail;
  }
  pthread_setname_np(h->thread, "controller_path");
  h->running = 1;
  return 0;
fail:
  entities_fini(h);
  return -1;
}

/* From now on the thread also takes the reference samples of topic (reliable, volatile, keep-last
 * depth) into the ring cp_references reads: the subscription is made here, in the calling thread,
 * on the node the thread runs on. Returns 0 (also when already on), or -1 (cp_error says why). */
int cp_follow_references(cp_t *h, const char *topic, int depth) {
  if (!h->thread) {
    snprintf(h->error, sizeof h->error, "the thread is not running");
    return -1;
  }
  if (ACQUIRE(h->refs_on)) return 0;
  h->ref_sub = rcl_get_zero_initialized_subscription();
  rcl_subscription_options_t so = rcl_subscription_get_default_options();
  so.qos = qos((size_t)depth, 0);
  if (rcl_subscription_init(&h->ref_sub, h->node,
                            ROSIDL_GET_MSG_TYPE_SUPPORT(trajectory_msgs, msg, MultiDOFJointTrajectory), topic,
                            &so) != RCL_RET_OK) {
    snprintf(h->error, sizeof h->error, "subscribing to the references: %s", rcl_get_error_string().str);
    rcl_reset_error();
    return -1;
  }
  RELEASE(h->refs_on, 1);    /* (after the subscription is made: the thread takes from it from now on) */
  return 0;
}

void cp_stop(cp_t *h) {
  if (!h->thread) return;
  RELEASE(h->stop, 1);
  RELEASE(h->rows_put, LOAD(h->rows_put) + 1);   /* a state waiting for its row stops waiting */
  futex(&h->rows_put, FUTEX_WAKE_PRIVATE, INT_MAX, NULL);
  pthread_join(h->thread, NULL);
  h->thread = 0;
  h->running = 0;
  entities_fini(h);
}

void cp_destroy(cp_t *h) {
  if (!h) return;
  cp_stop(h);
  pthread_mutex_destroy(&h->py);
  free(h->rows);
  free(h);
}
