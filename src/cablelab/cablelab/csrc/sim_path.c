/* The CDPR simulator node's per-period path in C (cablelab.plants.cdpr.sim_path loads it).
 *
 * A thread of its own steps the node's MuJoCo model on absolute deadlines of 1/rate s, with the
 * newest effort command (or the winch brakes), publishes the winch joint states, the cable
 * tensions and the reference sample due around each state through an rcl node of its own, and
 * appends each published sample (time, qpos, qvel, actuator forces, sensors, tendon lengths) to a
 * lock-free ring that the Python node drains to publish the rest off the deadline path. Its law is
 * SimStepper's in real time, step for step: at each deadline the newest command is taken (the
 * answer to the last state drives the step due, as SimStepper.step_ahead), and the steps due (at
 * most 20, the rest dropped) are counted late, stale (the command answers an older state) or
 * braked (no command for the command timeout) the same way. Messages go out as serialised bytes patched
 * in templates that Python built with rclpy (same layout, same type support); commands are taken
 * serialised and read like cablelab.ros.rawmsg.command_arrays. */
#define _GNU_SOURCE
#pragma STDC FP_CONTRACT OFF /* the same round-off as numpy: no fused multiply-adds */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mujoco/mujoco.h>
#include <rcl/rcl.h>
#include <rcl/error_handling.h>
#include <rcutils/error_handling.h>
#include <rmw/qos_profiles.h>
#include <rmw/serialized_message.h>

#include "sim_path.h"
#include "rt_common.h"

#define MAX_CATCH_UP 20

typedef struct {
  uint8_t *buf;
  size_t len;
  long sec, nsec, v[3]; /* byte offsets: stamp sec (int32), nanosec (uint32), three float64 arrays */
} Template;

struct SimPath {
  const mjModel *m;
  mjData *d;
  int n, nstep;
  double rate;
  int *reel_q, *reel_v;
  double *paid0, k, kp, kd, hold_scale;
  double torque_noise, tension_noise, *bias;
  uint64_t rng[4];
  int spare_ok;
  double spare;
  double timeout, duration;
  int mass_body;
  double mass, mass_time;
  /* reference: table rows (pos 3, vel 3, acc 3) at the rate's grid */
  const double *ref;
  long ref_rows;
  int ref_on, ref_lead, ref_started;
  Template js, rt, ten;
  /* ros */
  rcl_context_t ctx;
  rcl_node_t node;
  rcl_publisher_t pub_js, pub_ref, pub_ten;
  rcl_subscription_t sub;
  int ros_ok;
  rcl_serialized_message_t in;
  double *cmd;           /* scratch: the values of the command being read */
  /* the law's state */
  double *u, *hold, *lock_q;
  int have_u, has_stamp, braking, ahead;
  double u_stamp, last_good, wall0, work;
  long k_steps;
  long counts[SP_NCOUNTS];
  /* ring of published samples (single producer: the thread; single consumer: Python) */
  double *ring;
  long cap, stride;
  long head, tail;
  pthread_t th;
  int started, stop, finished;
  char error[256];
};

/* ---------------------------------------------------------------------------------- helpers */

static void count_add(SimPath *s, int i, long v) { __atomic_fetch_add(&s->counts[i], v, __ATOMIC_RELAXED); }

/* Once commands come: a delay of `dt` s raises the maximum counts[imax] (ns; this thread is its
 * only writer) and, over SLOW_PUBLISH, counts[islow] (when islow >= 0). */
#define SLOW_PUBLISH 2e-4
static void note_delay(SimPath *s, int imax, double dt, int islow) {
  if (__atomic_load_n(&s->counts[SP_COMMANDS], __ATOMIC_RELAXED) == 0) return;
  long ns = (long)(dt * 1e9);
  if (ns > __atomic_load_n(&s->counts[imax], __ATOMIC_RELAXED)) __atomic_store_n(&s->counts[imax], ns, __ATOMIC_RELAXED);
  if (islow >= 0 && dt > SLOW_PUBLISH) count_add(s, islow, 1);
}

/* xoshiro256** and the polar method: the torque sensor's noise (its own stream, seeded) */
static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
static uint64_t next_u64(uint64_t *st) {
  uint64_t r = rotl(st[1] * 5, 7) * 9, t = st[1] << 17;
  st[2] ^= st[0]; st[3] ^= st[1]; st[1] ^= st[2]; st[0] ^= st[3]; st[2] ^= t; st[3] = rotl(st[3], 45);
  return r;
}
static double uniform(SimPath *s) { return (next_u64(s->rng) >> 11) * 0x1.0p-53; }
static double normal(SimPath *s) {
  if (s->spare_ok) { s->spare_ok = 0; return s->spare; }
  double u, v, q;
  do {
    u = 2.0 * uniform(s) - 1.0;
    v = 2.0 * uniform(s) - 1.0;
    q = u * u + v * v;
  } while (q >= 1.0 || q == 0.0);
  double f = sqrt(-2.0 * log(q) / q);
  s->spare = v * f;
  s->spare_ok = 1;
  return u * f;
}

static void set_error(SimPath *s, const char *what) {
  snprintf(s->error, sizeof s->error, "%s: %s", what, rcutils_get_error_string().str);
  rcutils_reset_error();
}

/* ------------------------------------------------------------------------------- messages */
static void put_stamp(Template *t, double stamp) {
  long long ns = llround(stamp * 1e9);
  int32_t sec = (int32_t)(ns / 1000000000LL);
  uint32_t nsec = (uint32_t)(ns % 1000000000LL);
  memcpy(t->buf + t->sec, &sec, 4);
  memcpy(t->buf + t->nsec, &nsec, 4);
}

static void put_values(Template *t, int which, const double *v, int count) {
  memcpy(t->buf + t->v[which], v, sizeof(double) * count);
}

static int publish(SimPath *s, rcl_publisher_t *pub, Template *t) {
  rcl_serialized_message_t msg = rmw_get_zero_initialized_serialized_message();
  msg.buffer = t->buf;
  msg.buffer_length = t->len;
  msg.buffer_capacity = t->len;
  double t0 = now_s();
  int ok = rcl_publish_serialized_message(pub, &msg, NULL) == RCL_RET_OK;
  if (!ok) {
    rcutils_reset_error();
    count_add(s, SP_PUBLISH_ERRORS, 1);
  }
  note_delay(s, SP_PUBLISH_MAX_NS, now_s() - t0,
             pub == &s->pub_js ? SP_SLOW_JS : pub == &s->pub_ten ? SP_SLOW_TEN : SP_SLOW_REF);
  return ok;
}

/* The reference sample of stamp t (the table's row on the rate's grid; past the table: its last) */
static void publish_reference(SimPath *s, double t) {
  long row = lround(t * s->rate);
  if (row < 0) row = 0;
  if (row >= s->ref_rows) row = s->ref_rows - 1;
  const double *r = s->ref + 9 * row;
  put_stamp(&s->rt, t);
  put_values(&s->rt, 0, r, 3);
  put_values(&s->rt, 1, r + 3, 3);
  put_values(&s->rt, 2, r + 6, 3);
  publish(s, &s->pub_ref, &s->rt);
}

/* The motor sensors of the present state: angles, rates (noise-free), torques from current */
static void motor_angles(SimPath *s, double *angle) {
  for (int i = 0; i < s->n; i++) angle[i] = -s->k * (s->paid0[i] - s->d->qpos[s->reel_q[i]]);
}

static void publish_state(SimPath *s) {
  double t = s->d->time, a[SP_MAX_N], v[SP_MAX_N], e[SP_MAX_N];
  int lead = s->ref_lead;
  if (s->ref_on && lead == 0) publish_reference(s, t);
  if (s->ref_on && lead > 0 && !s->ref_started)
    for (int i = 0; i < lead; i++) publish_reference(s, t + i / s->rate);
  s->ref_started = 1;
  motor_angles(s, a);
  for (int i = 0; i < s->n; i++) {
    v[i] = s->k * s->d->qvel[s->reel_v[i]];
    e[i] = s->d->actuator_force[i] + s->torque_noise * normal(s);
  }
  put_stamp(&s->js, t);
  put_values(&s->js, 0, a, s->n);
  put_values(&s->js, 1, v, s->n);
  put_values(&s->js, 2, e, s->n);
  publish(s, &s->pub_js, &s->js);
  /* the dynamometers (noise, bias) and the paid-out lengths */
  for (int i = 0; i < s->n; i++) {
    a[i] = s->paid0[i] - s->d->qpos[s->reel_q[i]];
    e[i] = fabs(s->d->sensordata[i]) + s->bias[i] + s->tension_noise * normal(s);
  }
  put_stamp(&s->ten, t);
  put_values(&s->ten, 0, a, s->n);
  put_values(&s->ten, 1, e, s->n);
  publish(s, &s->pub_ten, &s->ten);
  if (s->ref_on && lead > 0) publish_reference(s, t + lead / s->rate);
}

/* Read one serialised std_msgs/Float64MultiArray (XCDR1, either byte order): its value count
 * (-1: not such a message) into s->cmd (at most cap values read), its label's stamp. */
static uint32_t rd32(const uint8_t *b, int swap) {
  uint32_t v;
  memcpy(&v, b, 4);
  return swap ? __builtin_bswap32(v) : v;
}

static long read_command(SimPath *s, const uint8_t *b, size_t n, int cap, double *stamp, int *has_stamp) {
  *has_stamp = 0;
  if (n < 12 || b[0] != 0 || b[1] > 1) return -1;
  int swap = (b[1] == 1) != (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__);
  size_t pos = 4;
#define WORD(out)                                  \
  do {                                             \
    pos += (4 - (pos - 4) % 4) % 4;                \
    if (pos + 4 > n) return -1;                    \
    out = rd32(b + pos, swap);                     \
    pos += 4;                                      \
  } while (0)
  uint32_t ndim, len, tmp, count;
  WORD(ndim);
  if (ndim > 64) return -1;
  for (uint32_t i = 0; i < ndim; i++) {
    WORD(len);
    if (len < 1 || pos + len > n) return -1;
    if (i == 0) {
      char label[128];
      size_t l = len - 1 < sizeof label - 1 ? len - 1 : sizeof label - 1;
      memcpy(label, b + pos, l);
      label[l] = 0;
      const char *p = strstr(label, "stamp=");
      if (p) {
        char *end;
        double t = strtod(p + 6, &end);
        if (end != p + 6 && isfinite(t)) { *stamp = t; *has_stamp = 1; }
      }
    }
    pos += len;
    WORD(tmp);
    WORD(tmp);
  }
  WORD(tmp); /* data_offset */
  WORD(count);
  (void)tmp;
  pos += (8 - (pos - 4) % 8) % 8;
  if (pos + 8 * (size_t)count > n) return -1;
  for (uint32_t i = 0; i < count && (int)i < cap; i++) {
    uint64_t w;
    memcpy(&w, b + pos + 8 * i, 8);
    if (swap) w = __builtin_bswap64(w);
    memcpy(&s->cmd[i], &w, 8);
  }
  return count;
#undef WORD
}

/* Take every queued command (keep-last 1: the newest); each one is checked like InputMonitor
 * (empty, wrong length, NaN: rejected and counted). 1 if a good one came. */
static int take_commands(SimPath *s) {
  int good = 0;
  rmw_message_info_t info;
  while (rcl_take_serialized_message(&s->sub, &s->in, &info, NULL) == RCL_RET_OK) {
    double stamp = 0.0;
    int has_stamp;
    long count = read_command(s, s->in.buffer, s->in.buffer_length, s->n, &stamp, &has_stamp);
    int problem = SP_PROBLEM_NONE;
    if (count <= 0) problem = SP_PROBLEM_EMPTY;
    else if (count != s->n) problem = SP_PROBLEM_LENGTH;
    else
      for (int i = 0; i < s->n; i++)
        if (!isfinite(s->cmd[i])) problem = SP_PROBLEM_NAN;
    if (problem != SP_PROBLEM_NONE) {
      __atomic_store_n(&s->counts[SP_LAST_PROBLEM], problem, __ATOMIC_RELAXED);
      __atomic_store_n(&s->counts[SP_LAST_BAD_LENGTH], count, __ATOMIC_RELAXED);
      count_add(s, SP_REJECTED, 1);
      continue;
    }
    memcpy(s->u, s->cmd, sizeof(double) * s->n);
    s->have_u = 1;
    s->has_stamp = has_stamp;
    s->u_stamp = stamp;
    s->last_good = now_s();
    __atomic_store_n(&s->counts[SP_LAST_GOOD_NS], (long)llround(s->last_good * 1e9), __ATOMIC_RELAXED);
    count_add(s, SP_COMMANDS, 1);
    good = 1;
  }
  return good;
}

/* --------------------------------------------------------------------------------- the law */
static long counted(SimPath *s, int i) { return __atomic_load_n(&s->counts[i], __ATOMIC_RELAXED); }

/* One control period of physics with the last command (fresh) or the winch brakes. */
static void step(SimPath *s, int fresh, int late) {
  const mjModel *m = s->m;
  mjData *d = s->d;
  int n = s->n, missed = late, commands = counted(s, SP_COMMANDS) > 0;
  double t0 = now_s();
  fresh = fresh && s->have_u;
  if (!fresh) {
    double a[SP_MAX_N];
    for (int j = 0; j < s->nstep; j++) {
      motor_angles(s, a);
      if (!s->braking) { /* lock where the winches are, holding the last command (else the tensions) */
        for (int i = 0; i < n; i++) {
          s->lock_q[i] = a[i];
          s->hold[i] = s->have_u ? s->u[i] : s->hold_scale * fabs(d->sensordata[i]);
        }
        s->braking = 1;
      }
      for (int i = 0; i < n; i++)
        d->ctrl[i] = s->hold[i] + s->kp * (s->lock_q[i] - a[i]) - s->kd * (s->k * d->qvel[s->reel_v[i]]);
      mj_step(m, d);
    }
    count_add(s, SP_FALLBACKS, 1);
    if (commands) { count_add(s, SP_FALLBACKS_RUNNING, 1); missed = 1; }
  } else {
    if (s->has_stamp) {
      long age = lround((d->time - s->u_stamp) * s->rate);
      count_add(s, SP_AGE1 + (age < 0 ? 0 : age > 2 ? 2 : (int)age), 1);
      if (age > 0) { count_add(s, SP_STALE, 1); missed = 1; }
    }
    s->braking = 0;
    for (int i = 0; i < n; i++) d->ctrl[i] = s->u[i];
    for (int j = 0; j < s->nstep; j++) mj_step(m, d);
  }
  s->k_steps++;
  count_add(s, SP_STEPS, 1);
  if (s->mass != 0.0 && s->mass_time >= 0 && s->mass_time <= d->time) {
    mjModel *mm = (mjModel *)m; /* the payload put on: the one change of the model while running */
    double m0 = mm->body_mass[s->mass_body], m1 = m0 + s->mass;
    if (m1 > 0) {
      mm->body_mass[s->mass_body] = m1;
      for (int i = 0; i < 3; i++) mm->body_inertia[3 * s->mass_body + i] *= m1 / m0;
      count_add(s, SP_MASS_CHANGED, 1);
    }
    s->mass = 0.0;
  }
  if (missed && commands) count_add(s, SP_MISSED, 1);
  for (int i = 0; i < m->ntendon; i++)
    if (d->ten_length[i] < m->tendon_range[2 * i + 1] - 1e-6) { count_add(s, SP_SLACK, 1); break; }
  if (s->duration > 0 && d->time >= s->duration) s->finished = 1;   /* (done once published) */
  s->work = now_s() - t0;
}

static void push_sample(SimPath *s, double work) {
  long head = s->head, tail = __atomic_load_n(&s->tail, __ATOMIC_ACQUIRE);
  if (head - tail >= s->cap) { count_add(s, SP_RING_LOST, 1); return; }
  const mjModel *m = s->m;
  const mjData *d = s->d;
  double *r = s->ring + (head % s->cap) * s->stride;
  r[0] = d->time;
  r[1] = (double)s->k_steps;
  r[2] = work;
  r[3] = (double)counted(s, SP_MASS_CHANGED);
  double *p = r + 4;
  memcpy(p, d->qpos, sizeof(double) * m->nq); p += m->nq;
  memcpy(p, d->qvel, sizeof(double) * m->nv); p += m->nv;
  memcpy(p, d->actuator_force, sizeof(double) * m->nu); p += m->nu;
  memcpy(p, d->sensordata, sizeof(double) * m->nsensordata); p += m->nsensordata;
  memcpy(p, d->ten_length, sizeof(double) * m->ntendon);
  __atomic_store_n(&s->head, head + 1, __ATOMIC_RELEASE);
}

/* The state of the last step goes out at its deadline (its work: computing it and publishing). */
static void publish_ready(SimPath *s, double work) {
  double t0 = now_s();
  publish_state(s);
  s->ahead = 0;
  push_sample(s, work + now_s() - t0);
  /* done only once its last sample is in the ring: Python reads the counts, then drains */
  if (s->finished) __atomic_store_n(&s->counts[SP_DONE], 1, __ATOMIC_RELEASE);
}

/* SimStepper.due: the steps due at `now` (the first on time, the rest late; far behind dropped) */
static long due_steps(SimPath *s, double now) {
  long published = s->k_steps - s->ahead, commands = counted(s, SP_COMMANDS) > 0;
  long due = (long)((now - s->wall0) * s->rate) - published;
  if (commands && due > 1) count_add(s, SP_LATE, (due < MAX_CATCH_UP ? due : MAX_CATCH_UP) - 1);
  if (due > MAX_CATCH_UP - 1) {
    if (commands) count_add(s, SP_DROPPED, due - MAX_CATCH_UP);
    s->wall0 = now - published / s->rate;
    due = MAX_CATCH_UP;
  }
  return due > 0 ? due : 0;
}

static int done(SimPath *s) { return __atomic_load_n(&s->counts[SP_DONE], __ATOMIC_ACQUIRE) != 0; }
static int stopping(SimPath *s) { return __atomic_load_n(&s->stop, __ATOMIC_ACQUIRE); }

/* A command answering the last published state drives the next step (fresh, whatever the
 * command timeout), computed now; the steps due then publish it first (SimStepper.step_ahead). */
static void answered_step(SimPath *s) {
  if (!s->ahead && !s->finished && s->has_stamp && fabs(s->u_stamp - s->d->time) < 0.5 / s->rate) {
    step(s, 1, 0);
    s->ahead = 1;
  }
}

/* The thread: sleep to the next absolute deadline, take the newest command (keep-last 1; no wait
 * set: polling at the deadline costs the least CPU), then the steps due (SimStepper.due). */
static void *run(void *arg) {
  SimPath *s = arg;
  double T = 1.0 / s->rate;
  s->wall0 = now_s() - (s->k_steps - s->ahead) * T;
  while (!stopping(s) && !done(s)) {
    double deadline = s->wall0 + (s->k_steps - s->ahead + 1) * T;
    sleep_until(deadline);
    note_delay(s, SP_WAKE_MAX_NS, now_s() - deadline, -1);
    if (take_commands(s)) answered_step(s);
    double now = now_s();
    long due = due_steps(s, now);
    for (long i = 0; i < due && !stopping(s); i++) {
      if (s->ahead) {
        publish_ready(s, s->work);
      } else {
        step(s, now - s->last_good <= s->timeout, i > 0);
        publish_ready(s, s->work);
      }
      if (done(s)) break;
    }
  }
  return NULL;
}

/* ------------------------------------------------------------------------------- interface */
SimPath *sp_new(const mjModel *m, mjData *d, int n, int nstep, double rate, long ring_capacity) {
  if (n < 1 || n > SP_MAX_N || m->nu < n || nstep < 1 || rate <= 0) return NULL;
  SimPath *s = calloc(1, sizeof *s);
  s->m = m;
  s->d = d;
  s->n = n;
  s->nstep = nstep;
  s->rate = rate;
  s->reel_q = calloc(n, sizeof(int));
  s->reel_v = calloc(n, sizeof(int));
  s->paid0 = calloc(n, sizeof(double));
  s->u = calloc(n, sizeof(double));
  s->hold = calloc(n, sizeof(double));
  s->lock_q = calloc(n, sizeof(double));
  s->cmd = calloc(n, sizeof(double));
  s->bias = calloc(n, sizeof(double));
  s->timeout = 0.2;
  s->mass_time = -1.0;
  s->cap = ring_capacity > 16 ? ring_capacity : 16;
  s->stride = sp_stride(m);
  s->ring = calloc((size_t)(s->cap * s->stride), sizeof(double));
  s->ctx = rcl_get_zero_initialized_context();
  s->node = rcl_get_zero_initialized_node();
  s->pub_js = rcl_get_zero_initialized_publisher();
  s->pub_ref = rcl_get_zero_initialized_publisher();
  s->pub_ten = rcl_get_zero_initialized_publisher();
  s->sub = rcl_get_zero_initialized_subscription();
  s->in = rmw_get_zero_initialized_serialized_message();
  return s;
}

long sp_stride(const mjModel *m) { return 4 + m->nq + m->nv + m->nu + m->nsensordata + m->ntendon; }

void sp_winches(SimPath *s, const int *reel_q, const int *reel_v, const double *paid0, double k,
                double kp, double kd, double hold_scale) {
  memcpy(s->reel_q, reel_q, sizeof(int) * s->n);
  memcpy(s->reel_v, reel_v, sizeof(int) * s->n);
  memcpy(s->paid0, paid0, sizeof(double) * s->n);
  s->k = k;
  s->kp = kp;
  s->kd = kd;
  s->hold_scale = hold_scale;
}

void sp_schedule(SimPath *s, double command_timeout, double duration, int mass_body, double mass,
                 double mass_time, double torque_noise, double tension_noise, const double *bias, uint64_t seed) {
  s->tension_noise = tension_noise;
  memcpy(s->bias, bias, sizeof(double) * s->n);
  s->timeout = command_timeout;
  s->duration = duration;
  s->mass_body = mass_body;
  s->mass = mass;
  s->mass_time = mass_time;
  s->torque_noise = torque_noise;
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL; /* splitmix64 seeds the generator */
  for (int i = 0; i < 4; i++) {
    z += 0x9E3779B97F4A7C15ULL;
    uint64_t x = z;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    s->rng[i] = x ^ (x >> 31);
  }
}

static void set_template(Template *t, const uint8_t *bytes, size_t len, long sec, long nsec, long v0, long v1,
                         long v2) {
  free(t->buf);
  t->buf = malloc(len);
  memcpy(t->buf, bytes, len);
  t->len = len;
  t->sec = sec;
  t->nsec = nsec;
  t->v[0] = v0;
  t->v[1] = v1;
  t->v[2] = v2;
}

void sp_joint_template(SimPath *s, const uint8_t *bytes, size_t len, long sec, long nsec, long pos, long vel,
                       long eff) {
  set_template(&s->js, bytes, len, sec, nsec, pos, vel, eff);
}

void sp_tension_template(SimPath *s, const uint8_t *bytes, size_t len, long sec, long nsec, long length,
                         long tension) {
  set_template(&s->ten, bytes, len, sec, nsec, length, tension, -1);
}

void sp_reference(SimPath *s, const uint8_t *bytes, size_t len, long sec, long nsec, long pos, long vel,
                  long acc, const double *table, long rows, int lead_steps) {
  set_template(&s->rt, bytes, len, sec, nsec, pos, vel, acc);
  s->ref = table;
  s->ref_rows = rows;
  s->ref_lead = lead_steps;
  s->ref_on = rows > 0;
}

/* Its own rcl context and node: publishers of the joint states, the tensions and the reference (reliable,
 * transient local, keep-last publisher_depth), the command subscription (reliable, volatile,
 * keep-last 1), in ROS domain `domain_id` (the Python node's). Type supports: rclpy's own (the
 * message classes' _TYPE_SUPPORT). 0 on success. */
int sp_ros(SimPath *s, const char *node_name, long domain_id, const void *ts_js, const char *js_topic,
           const char *ten_topic, const void *ts_ref, const char *ref_topic, const void *ts_cmd, const char *cmd_topic, long publisher_depth) {
  rcl_allocator_t alloc = rcl_get_default_allocator();
  rcl_init_options_t io = rcl_get_zero_initialized_init_options();
  if (rcl_init_options_init(&io, alloc) != RCL_RET_OK) { set_error(s, "rcl_init_options_init"); return 1; }
  if (domain_id >= 0 && rcl_init_options_set_domain_id(&io, (size_t)domain_id) != RCL_RET_OK) {
    set_error(s, "rcl_init_options_set_domain_id");
    return 1;
  }
  rcl_ret_t rc = rcl_init(0, NULL, &io, &s->ctx);
  (void)!rcl_init_options_fini(&io);
  if (rc != RCL_RET_OK) { set_error(s, "rcl_init"); return 1; }
  s->ros_ok = 1;
  rcl_node_options_t no = rcl_node_get_default_options();
  if (rcl_node_init(&s->node, node_name, "", &s->ctx, &no) != RCL_RET_OK) { set_error(s, "rcl_node_init"); return 1; }
  s->ros_ok = 2;
  rcl_publisher_options_t po = rcl_publisher_get_default_options();
  po.qos = qos((size_t)publisher_depth, 1);
  if (rcl_publisher_init(&s->pub_js, &s->node, ts_js, js_topic, &po) != RCL_RET_OK) {
    set_error(s, js_topic);
    return 1;
  }
  if (rcl_publisher_init(&s->pub_ten, &s->node, ts_js, ten_topic, &po) != RCL_RET_OK) {
    set_error(s, ten_topic);
    return 1;
  }
  if (ts_ref && rcl_publisher_init(&s->pub_ref, &s->node, ts_ref, ref_topic, &po) != RCL_RET_OK) {
    set_error(s, ref_topic);
    return 1;
  }
  rcl_subscription_options_t so = rcl_subscription_get_default_options();
  so.qos = qos(1, 0);
  if (rcl_subscription_init(&s->sub, &s->node, ts_cmd, cmd_topic, &so) != RCL_RET_OK) {
    set_error(s, cmd_topic);
    return 1;
  }
  if (rmw_serialized_message_init(&s->in, 1024, &alloc) != RMW_RET_OK) { set_error(s, "serialized message"); return 1; }
  s->ros_ok = 3;
  return 0;
}

const char *sp_error(SimPath *s) { return s->error; }

/* Before the thread runs (the start gate): publish the present state (and its reference). */
void sp_publish_now(SimPath *s) {
  if (!s->started) publish_state(s);
}

int sp_start(SimPath *s) {
  if (s->started || s->ros_ok < 3) return 1;
  __atomic_store_n(&s->stop, 0, __ATOMIC_RELEASE);
  if (pthread_create(&s->th, NULL, run, s) != 0) return 1;
  pthread_setname_np(s->th, "sim_path");
  s->started = 1;
  return 0;
}

void sp_stop(SimPath *s) {
  if (!s->started) return;
  __atomic_store_n(&s->stop, 1, __ATOMIC_RELEASE);
  pthread_join(s->th, NULL);
  s->started = 0;
}

int sp_running(SimPath *s) { return s->started && !done(s); }

/* Up to `max` samples of the ring into `out` (max * stride doubles); how many. */
long sp_drain(SimPath *s, double *out, long max) {
  long tail = s->tail, head = __atomic_load_n(&s->head, __ATOMIC_ACQUIRE), got = 0;
  while (tail < head && got < max) {
    memcpy(out + got * s->stride, s->ring + (tail % s->cap) * s->stride, sizeof(double) * s->stride);
    tail++;
    got++;
  }
  __atomic_store_n(&s->tail, tail, __ATOMIC_RELEASE);
  return got;
}

void sp_counts(SimPath *s, long *out) {
  for (int i = 0; i < SP_NCOUNTS; i++) out[i] = __atomic_load_n(&s->counts[i], __ATOMIC_RELAXED);
}

int sp_subscribers(SimPath *s) {
  size_t c = 0;
  if (s->ros_ok < 3 || rcl_publisher_get_subscription_count(&s->pub_js, &c) != RCL_RET_OK) {
    rcutils_reset_error();
    return -1;
  }
  return (int)c;
}

/* Whether every reliable subscriber acknowledged what was published, waiting up to `timeout` s. */
int sp_all_acked(SimPath *s, double timeout) {
  if (s->ros_ok < 3) return 1;
  rcl_duration_value_t ns = (rcl_duration_value_t)(timeout * 1e9);
  int ok = rcl_publisher_wait_for_all_acked(&s->pub_js, ns) == RCL_RET_OK;
  ok = (rcl_publisher_wait_for_all_acked(&s->pub_ten, ns) == RCL_RET_OK) && ok;
  if (s->ref_on) ok = (rcl_publisher_wait_for_all_acked(&s->pub_ref, ns) == RCL_RET_OK) && ok;
  rcutils_reset_error();
  return ok;
}

void sp_free(SimPath *s) {
  if (!s) return;
  sp_stop(s);
  if (s->ros_ok >= 3) {
    (void)!rmw_serialized_message_fini(&s->in);
  }
  if (s->ros_ok >= 2) {
    (void)!rcl_subscription_fini(&s->sub, &s->node);
    (void)!rcl_publisher_fini(&s->pub_js, &s->node);
    (void)!rcl_publisher_fini(&s->pub_ref, &s->node);
    (void)!rcl_publisher_fini(&s->pub_ten, &s->node);
    (void)!rcl_node_fini(&s->node);
  }
  if (s->ros_ok >= 1) {
    (void)!rcl_shutdown(&s->ctx);
    (void)!rcl_context_fini(&s->ctx);
  }
  rcutils_reset_error();
  free(s->reel_q); free(s->reel_v); free(s->paid0); free(s->u); free(s->hold); free(s->lock_q); free(s->cmd); free(s->bias);
  free(s->ring); free(s->js.buf); free(s->rt.buf); free(s->ten.buf);
  free(s);
}

/* ---------------------------------------------------------------- the law without ROS (tests) */
/* Step the law as the thread does, without ROS and without clocks: command i (n values, NaN
 * first value: none came, the brakes hold) drives step i; fresh commands answer the last state. */
void sp_run_commands(SimPath *s, const double *commands, long count) {
  for (long i = 0; i < count; i++) {
    const double *c = commands + i * s->n;
    int fresh = !isnan(c[0]);
    if (fresh) {
      memcpy(s->u, c, sizeof(double) * s->n);
      s->have_u = 1;
      s->has_stamp = 1;
      s->u_stamp = s->d->time;
      count_add(s, SP_COMMANDS, 1);
    }
    step(s, fresh, 0);
    push_sample(s, s->work);
    if (s->finished) __atomic_store_n(&s->counts[SP_DONE], 1, __ATOMIC_RELEASE);
  }
}
