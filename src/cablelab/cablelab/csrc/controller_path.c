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
 * path). A state newer than every row waits up to row_wait s for Python to plan its row first. */
#define _GNU_SOURCE
#pragma STDC FP_CONTRACT OFF
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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

enum { CP_OK = 0, CP_NO_ROW = 1, CP_BAD_STATE = 2 };

typedef struct {
  double t;
  double pd[CP_MAXN], ff[4][CP_MAXN], fric[CP_MAXN];
} Row;

typedef struct {
  int n, has_ff;
  double kp, kd, k, t_min, max_torque, row_wait, estimate_timeout;
  double est_t, est_c[4], nominal_c[4]; /* the live estimate's stamp (NaN: none) and weights */
  pthread_mutex_t mu;
  pthread_cond_t rows_put;
  Row *rows;
  long nrows;           /* rows ever appended; the newest is rows[(nrows - 1) % CP_ROWS] */
  /* handed to Python: the newest state this path did not answer */
  int handoff_ready, h_nq, h_nqd;
  double h_t, h_wall, h_q[CP_HANDOFF], h_qd[CP_HANDOFF];
  /* counters (Python reads them for /diagnostics) */
  long commanded, handed_off, waited, publish_failed, taken, wakes;
  long publish_slow;    /* rcl_publish calls that took longer than SLOW_PUBLISH */
  double publish_max;   /* s, the longest rcl_publish */
  double last_commanded_t, last_commanded_wall, last_taken_t;
  double lat[CP_LAT];
  long nlat;
  /* reference samples taken by the thread (cp_follow_references), read by Python */
  int refs_on;
  double refs[CP_REFS][CP_REF_COLS];
  long nrefs, refs_read, refs_lost;
  /* the thread and its rcl entities (on the caller's node) */
  pthread_t thread;
  int running;
  volatile int stop;
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
  h->est_t = NAN;
  h->nominal_c[0] = 1.0; h->nominal_c[1] = nominal_mass;
  h->last_commanded_t = NAN; h->last_commanded_wall = NAN; h->last_taken_t = NAN;
  pthread_mutex_init(&h->mu, NULL);
  pthread_condattr_t ca;
  pthread_condattr_init(&ca);
  pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
  pthread_cond_init(&h->rows_put, &ca);
  pthread_condattr_destroy(&ca);
  return h;
}

/* the row of stamp t (mutex held), or NULL */
static const Row *find_row(const cp_t *h, double t) {
  long lo = h->nrows > CP_ROWS ? h->nrows - CP_ROWS : 0;
  for (long i = h->nrows - 1; i >= lo; i--) {
    const Row *r = &h->rows[i % CP_ROWS];
    if (fabs(r->t - t) <= STAMP_TOL) return r;
    if (r->t < t - STAMP_TOL) break; /* rows are in stamp order */
  }
  return NULL;
}

static double newest_row_t(const cp_t *h) { return h->nrows ? h->rows[(h->nrows - 1) % CP_ROWS].t : -INFINITY; }

/* Put `count` rows (stamps t (count,), pd and fric (count, n), ff (count, 4, n) the tension terms
 * (NULL for PD), row-major): a stamp already kept is replaced, a newer one appended; an older stamp
 * that is not kept is ignored. Returns how many were kept. */
int cp_put_rows(cp_t *h, int count, const double *t, const double *pd, const double *ff, const double *fric) {
  int n = h->n, kept = 0;
  pthread_mutex_lock(&h->mu);
  for (int k = 0; k < count; k++) {
    if (!isfinite(t[k])) continue;
    Row *r;
    if (t[k] > newest_row_t(h) + STAMP_TOL) {
      r = &h->rows[h->nrows % CP_ROWS];
      h->nrows++;
    } else if (!(r = (Row *)find_row(h, t[k]))) {
      continue;
    }
    r->t = t[k];
    memcpy(r->pd, pd + (size_t)k * n, sizeof(double) * n);
    for (int i = 0; i < 4; i++) {
      if (ff) memcpy(r->ff[i], ff + ((size_t)k * 4 + i) * n, sizeof(double) * n);
      else memset(r->ff[i], 0, sizeof(double) * n);
    }
    memcpy(r->fric, fric + (size_t)k * n, sizeof(double) * n);
    kept++;
  }
  pthread_cond_broadcast(&h->rows_put);
  pthread_mutex_unlock(&h->mu);
  return kept;
}

static int good_state(const cp_t *h, double t, const double *q, int nq, const double *qd, int nqd) {
  if (!isfinite(t) || nq != h->n || nqd != h->n) return 0;
  for (int j = 0; j < nq; j++)
    if (!isfinite(q[j]) || !isfinite(qd[j])) return 0;
  return 1;
}

/* The live estimate: its stamp t_est and weights c = (1, m, m x_G, m y_G). A row of a stamp more
 * than estimate_timeout after t_est (or t_est NaN: no estimate) takes the nominal mass's
 * (1, m_nominal, 0, 0). */
void cp_set_estimate(cp_t *h, double t_est, double c0, double c1, double c2, double c3) {
  pthread_mutex_lock(&h->mu);
  h->est_t = t_est;
  h->est_c[0] = c0; h->est_c[1] = c1; h->est_c[2] = c2; h->est_c[3] = c3;
  pthread_mutex_unlock(&h->mu);
}

/* mutex held */
static int law_locked(const cp_t *h, double t, const double *q, const double *qd, double *out) {
  const Row *r = find_row(h, t);
  if (!r) return CP_NO_ROW;
  const double *c = isfinite(h->est_t) && t - h->est_t <= h->estimate_timeout ? h->est_c : h->nominal_c;
  double floor_ = h->k * h->t_min;
  for (int j = 0; j < h->n; j++) {
    double tau = r->pd[j] - h->kp * q[j];
    tau -= h->kd * qd[j];
    if (h->has_ff) {
      double ff = c[0] * r->ff[0][j] + c[1] * r->ff[1][j] + c[2] * r->ff[2][j] + c[3] * r->ff[3][j];
      ff = ff > h->t_min ? ff : h->t_min;
      tau += ff * h->k;
    }
    tau = tau > floor_ ? tau : floor_;
    tau += r->fric[j];
    tau = tau > -h->max_torque ? tau : -h->max_torque;
    out[j] = tau < h->max_torque ? tau : h->max_torque;
  }
  return CP_OK;
}

/* The torques (n,) for the motor state (q (nq,), q' (nqd,)) of stamp t: CP_OK, CP_NO_ROW (no row
 * of that stamp) or CP_BAD_STATE (not finite, wrong length); out untouched unless CP_OK. */
int cp_law(cp_t *h, double t, const double *q, int nq, const double *qd, int nqd, double *out) {
  if (!good_state(h, t, q, nq, qd, nqd)) return CP_BAD_STATE;
  pthread_mutex_lock(&h->mu);
  int rc = law_locked(h, t, q, qd, out);
  pthread_mutex_unlock(&h->mu);
  return rc;
}

/* The newest handed-off state, if one came since the last call: 1 and its stamp, wall time of
 * arrival (CLOCK_MONOTONIC, as Python's time.monotonic), lengths and up to cap values each. */
int cp_handoff(cp_t *h, double *t, double *wall, double *q, int *nq, double *qd, int *nqd, int cap) {
  pthread_mutex_lock(&h->mu);
  int ready = h->handoff_ready;
  if (ready) {
    *t = h->h_t; *wall = h->h_wall; *nq = h->h_nq; *nqd = h->h_nqd;
    int a = h->h_nq < cap ? h->h_nq : cap, b = h->h_nqd < cap ? h->h_nqd : cap;
    if (a > CP_HANDOFF) a = CP_HANDOFF;
    if (b > CP_HANDOFF) b = CP_HANDOFF;
    memcpy(q, h->h_q, sizeof(double) * (a > 0 ? a : 0));
    memcpy(qd, h->h_qd, sizeof(double) * (b > 0 ? b : 0));
    h->handoff_ready = 0;
  }
  pthread_mutex_unlock(&h->mu);
  return ready;
}

/* out[0..13]: commanded, handed off, waited for a row, publish failures, running (1/0, -1 failed),
 * stamp and wall time of the last command, states taken, wake-ups of the thread, stamp of the
 * last state taken, command publishes over SLOW_PUBLISH, the longest publish (s), reference samples
 * taken, reference samples lost (not read by Python before the ring wrapped) */
void cp_stats(cp_t *h, double *out) {
  pthread_mutex_lock(&h->mu);
  out[0] = h->commanded; out[1] = h->handed_off; out[2] = h->waited; out[3] = h->publish_failed;
  out[4] = h->running; out[5] = h->last_commanded_t; out[6] = h->last_commanded_wall;
  out[7] = h->taken; out[8] = h->wakes; out[9] = h->last_taken_t;
  out[10] = h->publish_slow; out[11] = h->publish_max; out[12] = h->nrefs; out[13] = h->refs_lost;
  pthread_mutex_unlock(&h->mu);
}

/* The take -> published times (s) since the last call, at most cap (the newest). */
int cp_latencies(cp_t *h, double *out, int cap) {
  pthread_mutex_lock(&h->mu);
  long n = h->nlat < CP_LAT ? h->nlat : CP_LAT;
  if (n > cap) n = cap;
  for (long i = 0; i < n; i++) out[i] = h->lat[(h->nlat - n + i) % CP_LAT];
  h->nlat = 0;
  pthread_mutex_unlock(&h->mu);
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
  pthread_mutex_lock(&h->mu);
  int on = h->refs_on;
  pthread_mutex_unlock(&h->mu);
  if (!on) return;
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
    pthread_mutex_lock(&h->mu);
    if (h->nrefs - h->refs_read >= CP_REFS) {     /* Python fell 2 s behind: the oldest unread is lost */
      h->refs_read++;
      h->refs_lost++;
    }
    memcpy(h->refs[h->nrefs % CP_REFS], row, sizeof row);
    h->nrefs++;
    pthread_mutex_unlock(&h->mu);
  }
  rcl_reset_error();
}

/* The reference samples taken since the last call, oldest first, at most cap rows of
 * CP_REF_COLS doubles (t, has position (1/0), position x y z, quaternion x y z w, linear velocity,
 * linear acceleration; NaN where the message has none); returns how many. */
int cp_references(cp_t *h, double *out, int cap) {
  pthread_mutex_lock(&h->mu);
  long n = h->nrefs - h->refs_read;
  if (n > cap) n = cap;
  for (long i = 0; i < n; i++)
    memcpy(out + i * CP_REF_COLS, h->refs[(h->refs_read + i) % CP_REFS], sizeof(double) * CP_REF_COLS);
  h->refs_read += n;
  pthread_mutex_unlock(&h->mu);
  return (int)n;
}

static void *run(void *arg) {
  cp_t *h = arg;
  double tau[CP_MAXN];
  char label[128];
  while (!h->stop) {
    if (rcl_wait_set_clear(&h->ws) != RCL_RET_OK || rcl_wait_set_add_subscription(&h->ws, &h->sub, NULL) != RCL_RET_OK) {
      rcl_reset_error();
      break;
    }
    rcl_ret_t rc = rcl_wait(&h->ws, RCL_MS_TO_NS(20));
    h->wakes++;
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
    pthread_mutex_lock(&h->mu);
    h->taken++;
    if (isfinite(t)) h->last_taken_t = t;
    if (good_state(h, t, q, nq, qd, nqd)) {
      res = law_locked(h, t, q, qd, tau);
      if (res == CP_NO_ROW && t > newest_row_t(h) + STAMP_TOL && h->row_wait > 0) {
        /* the reference of this stamp not planned yet: wait for Python to put its row */
        h->waited++;
        double until = wall + h->row_wait;
        while (res == CP_NO_ROW && !h->stop && t > newest_row_t(h) + STAMP_TOL) {
          double left = until - now_s();
          if (left <= 0) break;
          struct timespec abs_;
          clock_gettime(CLOCK_MONOTONIC, &abs_);
          double s = abs_.tv_sec + 1e-9 * abs_.tv_nsec + left;
          abs_.tv_sec = (time_t)s;
          abs_.tv_nsec = (long)((s - (double)abs_.tv_sec) * 1e9);
          pthread_cond_timedwait(&h->rows_put, &h->mu, &abs_);
        }
        res = law_locked(h, t, q, qd, tau);
      }
    }
    if (res != CP_OK) {
      h->handoff_ready = 1;
      h->handed_off++;
      h->h_t = t; h->h_wall = wall; h->h_nq = nq; h->h_nqd = nqd;
      memcpy(h->h_q, q, sizeof(double) * (nq < CP_HANDOFF ? nq : CP_HANDOFF));
      memcpy(h->h_qd, qd, sizeof(double) * (nqd < CP_HANDOFF ? nqd : CP_HANDOFF));
    }
    pthread_mutex_unlock(&h->mu);
    if (res != CP_OK) continue;
    memcpy(h->cmd.data.data, tau, sizeof(double) * h->n);
    snprintf(label, sizeof label, "%s stamp=%.9f", h->label, t);
    rosidl_runtime_c__String__assign(&h->cmd.layout.dim.data[0].label, label);
    double sent_at = now_s();
    int ok = rcl_publish(&h->pub, &h->cmd, NULL) == RCL_RET_OK;
    if (!ok) rcl_reset_error();
    double done_at = now_s();
    pthread_mutex_lock(&h->mu);
    if (done_at - sent_at > SLOW_PUBLISH) h->publish_slow++;
    if (done_at - sent_at > h->publish_max) h->publish_max = done_at - sent_at;
    if (ok) {
      h->commanded++;
      h->last_commanded_t = t;
      h->last_commanded_wall = done_at;
      h->lat[h->nlat++ % CP_LAT] = done_at - wall;
    } else {
      h->publish_failed++;
    }
    pthread_mutex_unlock(&h->mu);
    take_references(h);     /* after the command: off the state -> command path */
  }
  return NULL;
}

static void entities_fini(cp_t *h) {
  if (!h->node) return;
  (void)!rcl_wait_set_fini(&h->ws);
  (void)!rcl_subscription_fini(&h->sub, h->node);
  if (h->refs_on) (void)!rcl_subscription_fini(&h->ref_sub, h->node);
  h->refs_on = 0;
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
  h->stop = 0;
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
  pthread_mutex_lock(&h->mu);
  int on = h->refs_on;
  pthread_mutex_unlock(&h->mu);
  if (on) return 0;
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
  pthread_mutex_lock(&h->mu);
  h->refs_on = 1;
  pthread_mutex_unlock(&h->mu);
  return 0;
}

void cp_stop(cp_t *h) {
  if (!h->thread) return;
  h->stop = 1;
  pthread_mutex_lock(&h->mu);
  pthread_cond_broadcast(&h->rows_put);
  pthread_mutex_unlock(&h->mu);
  pthread_join(h->thread, NULL);
  h->thread = 0;
  h->running = 0;
  entities_fini(h);
}

void cp_destroy(cp_t *h) {
  if (!h) return;
  cp_stop(h);
  pthread_mutex_destroy(&h->mu);
  pthread_cond_destroy(&h->rows_put);
  free(h->rows);
  free(h);
}
