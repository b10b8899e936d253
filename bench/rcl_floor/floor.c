/* The floor of the 1 kHz closed loop: a simulator and a controller written against rcl in C (no
 * Python, no executor), over the same Fast DDS, on the same machine, without real-time
 * privileges. bench/bench_rcl_floor.py builds and runs it; this is a benchmark baseline, not a
 * node of cablelab (its physics is a bare mj_step holding the CDPR at its start pose).
 *
 *   floor sim  MODEL.mjb STATE.txt SECONDS RATE_HZ   (STATE.txt: nq qpos, nv qvel, nu ctrl)
 *   floor ctrl [STATE_TOPIC COMMAND_TOPIC]   (default /floor/joint_states /floor/effort_commands)
 *   floor timer SECONDS RATE_HZ   (the bare timer: deadlines only)
 *
 * sim: publishes the state of sim time k/RATE on /floor/joint_states (sensor_msgs/JointState,
 *   8 winches: qpos, qvel, effort = ctrl) and /floor/cable_tensions (std_msgs/Float64MultiArray,
 *   8 values) after one mj_step per period, at absolute 1/RATE deadlines (clock_nanosleep).
 *   Before time starts it republishes state 0 every 100 ms until a command answers it. Per step
 *   (counted after the first second, as bench_realtime does) it counts: late (woke a period or
 *   more after the deadline), stale (the newest command does not answer the last published
 *   state), dropped (more than 20 periods behind: skipped); a missed cycle is a step that is
 *   late or stale, plus the dropped ones. In-loop latency: wake-up to the state published.
 * ctrl: waits on /floor/joint_states, takes the newest, answers with
 *   /floor/effort_commands (Float64MultiArray, layout label "winches stamp=<t>" as cablelab's
 *   controllers send, u = the first state's effort - 0.001 qvel: it holds the start pose; with
 *   /cdpr/joint_states /cdpr/effort_commands it answers cablelab's CDPR simulator); latency:
 *   take to published. Stops after 2 s
 *   without states once started, or on SIGINT/SIGTERM.
 * Both print one JSON line of statistics on stdout at the end. */
#define _GNU_SOURCE
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mujoco/mujoco.h>
#include <rcl/rcl.h>
#include <rcl/error_handling.h>
#include <rcutils/error_handling.h>
#include <rmw/qos_profiles.h>
#include <rosidl_runtime_c/primitives_sequence_functions.h>
#include <rosidl_runtime_c/string_functions.h>
#include <sensor_msgs/msg/joint_state.h>
#include <std_msgs/msg/float64_multi_array.h>
#include <std_msgs/msg/multi_array_dimension.h>

#define N 8
#define CHECK(x)                                                                  \
  do {                                                                            \
    rcl_ret_t rc_ = (x);                                                          \
    if (rc_ != RCL_RET_OK) {                                                      \
      fprintf(stderr, "floor: %s failed: %s\n", #x, rcutils_get_error_string().str); \
      exit(2);                                                                    \
    }                                                                             \
  } while (0)

static volatile sig_atomic_t stop_requested = 0;
static void on_signal(int sig) { (void)sig; stop_requested = 1; }

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void sleep_until(double t) {
  struct timespec ts;
  ts.tv_sec = (time_t)t;
  ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
  if (ts.tv_nsec >= 1000000000L) { ts.tv_sec += 1; ts.tv_nsec -= 1000000000L; }
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR && !stop_requested) {}
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* p99 of each full window of `w` samples; returns the worst (ms) and the whole-run p99 in *all. */
static double worst_window_p99(double *v, size_t n, size_t w, double *all) {
  double worst = 0.0;
  double *tmp = malloc(sizeof(double) * (n > w ? n : w) + 1);
  for (size_t i = 0; i + w <= n; i += w) {
    memcpy(tmp, v + i, sizeof(double) * w);
    qsort(tmp, w, sizeof(double), cmp_double);
    double p = tmp[(size_t)(0.99 * (w - 1))];
    if (p > worst) worst = p;
  }
  memcpy(tmp, v, sizeof(double) * n);
  qsort(tmp, n, sizeof(double), cmp_double);
  *all = n ? tmp[(size_t)(0.99 * (n - 1))] : NAN;
  free(tmp);
  return worst;
}

static double cpu_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

typedef struct {
  rcl_context_t context;
  rcl_node_t node;
} Ros;

static void ros_init(Ros *r, const char *name) {
  rcl_allocator_t alloc = rcl_get_default_allocator();
  rcl_init_options_t io = rcl_get_zero_initialized_init_options();
  CHECK(rcl_init_options_init(&io, alloc));
  r->context = rcl_get_zero_initialized_context();
  CHECK(rcl_init(0, NULL, &io, &r->context));
  r->node = rcl_get_zero_initialized_node();
  rcl_node_options_t no = rcl_node_get_default_options();
  CHECK(rcl_node_init(&r->node, name, "", &r->context, &no));
}

static rmw_qos_profile_t stream_qos(size_t depth) {
  rmw_qos_profile_t q = rmw_qos_profile_default; /* reliable, volatile, keep last */
  q.history = RMW_QOS_POLICY_HISTORY_KEEP_LAST;
  q.depth = depth;
  q.reliability = RMW_QOS_POLICY_RELIABILITY_RELIABLE;
  q.durability = RMW_QOS_POLICY_DURABILITY_VOLATILE;
  return q;
}

static void array_msg_init(std_msgs__msg__Float64MultiArray *m, const char *label) {
  std_msgs__msg__Float64MultiArray__init(m);
  std_msgs__msg__MultiArrayDimension__Sequence__init(&m->layout.dim, 1);
  rosidl_runtime_c__String__assign(&m->layout.dim.data[0].label, label);
  m->layout.dim.data[0].size = N;
  m->layout.dim.data[0].stride = N;
  rosidl_runtime_c__double__Sequence__init(&m->data, N);
}

static double stamp_of(const builtin_interfaces__msg__Time *t) { return t->sec + 1e-9 * t->nanosec; }

static void set_stamp(builtin_interfaces__msg__Time *t, double s) {
  t->sec = (int32_t)floor(s);
  t->nanosec = (uint32_t)llround((s - floor(s)) * 1e9);
  if (t->nanosec >= 1000000000u) { t->sec += 1; t->nanosec -= 1000000000u; }
}

/* ------------------------------------------------------------------------------------ sim */
static int run_sim(const char *model_path, const char *state_path, double seconds, double rate) {
  mjModel *m = mj_loadModel(model_path, NULL);
  if (!m) { fprintf(stderr, "floor: cannot load %s\n", model_path); return 2; }
  mjData *d = mj_makeData(m);
  FILE *f = fopen(state_path, "r");
  if (!f) { fprintf(stderr, "floor: cannot open %s\n", state_path); return 2; }
  for (int i = 0; i < m->nq; i++) if (fscanf(f, "%lf", &d->qpos[i]) != 1) { fprintf(stderr, "floor: %s: short qpos\n", state_path); return 2; }
  for (int i = 0; i < m->nv; i++) if (fscanf(f, "%lf", &d->qvel[i]) != 1) { fprintf(stderr, "floor: %s: short qvel\n", state_path); return 2; }
  for (int i = 0; i < m->nu; i++) if (fscanf(f, "%lf", &d->ctrl[i]) != 1) { fprintf(stderr, "floor: %s: short ctrl\n", state_path); return 2; }
  fclose(f);
  mjtNum hold[64];
  int nu = m->nu < 64 ? m->nu : 64;
  for (int i = 0; i < nu; i++) hold[i] = d->ctrl[i];
  mj_forward(m, d);

  Ros r;
  ros_init(&r, "floor_sim");
  const rosidl_message_type_support_t *ts_js = ROSIDL_GET_MSG_TYPE_SUPPORT(sensor_msgs, msg, JointState);
  const rosidl_message_type_support_t *ts_arr = ROSIDL_GET_MSG_TYPE_SUPPORT(std_msgs, msg, Float64MultiArray);
  rcl_publisher_t pub_js = rcl_get_zero_initialized_publisher(), pub_t = rcl_get_zero_initialized_publisher();
  rcl_publisher_options_t po = rcl_publisher_get_default_options();
  po.qos = stream_qos(2000);
  CHECK(rcl_publisher_init(&pub_js, &r.node, ts_js, "/floor/joint_states", &po));
  CHECK(rcl_publisher_init(&pub_t, &r.node, ts_arr, "/floor/cable_tensions", &po));
  rcl_subscription_t sub = rcl_get_zero_initialized_subscription();
  rcl_subscription_options_t so = rcl_subscription_get_default_options();
  so.qos = stream_qos(1);
  CHECK(rcl_subscription_init(&sub, &r.node, ts_arr, "/floor/effort_commands", &so));

  sensor_msgs__msg__JointState js;
  sensor_msgs__msg__JointState__init(&js);
  rosidl_runtime_c__String__Sequence__init(&js.name, N);
  for (int i = 0; i < N; i++) {
    char nm[32];
    snprintf(nm, sizeof nm, "winch_%d", i + 1);
    rosidl_runtime_c__String__assign(&js.name.data[i], nm);
  }
  rosidl_runtime_c__double__Sequence__init(&js.position, N);
  rosidl_runtime_c__double__Sequence__init(&js.velocity, N);
  rosidl_runtime_c__double__Sequence__init(&js.effort, N);
  std_msgs__msg__Float64MultiArray tens, cmd;
  array_msg_init(&tens, "cables");
  std_msgs__msg__Float64MultiArray__init(&cmd);

  double T = 1.0 / rate, t_state = 0.0;
  long slow_js = 0;     /* joint-state publishes over 0.2 ms, counted as cablelab's sim_path does */
  int counting_js = 0;
  #define PUBLISH_STATE(t)                                                           \
    do {                                                                             \
      set_stamp(&js.header.stamp, (t));                                              \
      for (int i = 0; i < N; i++) {                                                  \
        js.position.data[i] = d->qpos[i % m->nq];                                    \
        js.velocity.data[i] = d->qvel[i % m->nv];                                    \
        js.effort.data[i] = d->ctrl[i % (m->nu ? m->nu : 1)];                        \
        tens.data.data[i] = d->actuator_force[i % (m->nu ? m->nu : 1)];              \
      }                                                                              \
      double t_js_ = now_s();                                                        \
      CHECK(rcl_publish(&pub_js, &js, NULL));                                        \
      slow_js += counting_js && now_s() - t_js_ > 2e-4;                              \
      CHECK(rcl_publish(&pub_t, &tens, NULL));                                       \
      t_state = (t);                                                                 \
    } while (0)

  /* start: state 0 until a command answers it (at most 60 s) */
  double t_wait0 = now_s(), last_pub = -1.0;
  int answered = 0;
  while (!answered && !stop_requested && now_s() - t_wait0 < 60.0) {
    if (now_s() - last_pub > 0.1) { PUBLISH_STATE(0.0); last_pub = now_s(); }
    rmw_message_info_t info;
    while (rcl_take(&sub, &cmd, &info, NULL) == RCL_RET_OK) {
      const char *lab = cmd.layout.dim.size ? cmd.layout.dim.data[0].label.data : "";
      const char *s = strstr(lab, "stamp=");
      if (s && fabs(atof(s + 6) - t_state) < 1e-7) answered = 1;
    }
    struct timespec ts = {0, 1000000};
    nanosleep(&ts, NULL);
  }
  if (!answered) { fprintf(stderr, "floor sim: no command answered state 0 within 60 s\n"); return 2; }

  long n = (long)llround(seconds * rate), warm = (long)llround(rate); /* first second not counted */
  double *lat = malloc(sizeof(double) * (n + 1));
  long nlat = 0, late = 0, stale = 0, dropped = 0, missed = 0, counted = 0;
  double start = now_s(), cpu0 = 0.0, wall0 = 0.0;
  long k = 0;
  while (k < n && !stop_requested) {
    double due = start + k * T;
    sleep_until(due);
    double woke = now_s();
    int counting = k >= warm;
    if (k == warm) { cpu0 = cpu_s(); wall0 = woke; counting_js = 1; }
    double behind = woke - due;
    if (behind > 20 * T) { /* too far behind: skip the periods already past */
      long skip = (long)(behind / T);
      if (counting) { dropped += skip; missed += skip; }
      k += skip;
      continue;
    }
    int is_late = behind >= T, is_stale = 1;
    rmw_message_info_t info;
    while (rcl_take(&sub, &cmd, &info, NULL) == RCL_RET_OK) {
      const char *lab = cmd.layout.dim.size ? cmd.layout.dim.data[0].label.data : "";
      const char *s = strstr(lab, "stamp=");
      int fresh = s && fabs(atof(s + 6) - t_state) < 1e-7;
      if (fresh && cmd.data.size >= (size_t)nu) {
        for (int i = 0; i < nu; i++) d->ctrl[i] = isfinite(cmd.data.data[i]) ? cmd.data.data[i] : hold[i];
      }
      is_stale = !fresh;
    }
    mj_step(m, d);
    PUBLISH_STATE((k + 1) * T);
    if (counting) {
      counted++;
      late += is_late;
      stale += is_stale;
      missed += is_late || is_stale;
      lat[nlat++] = 1e3 * (now_s() - woke);
    }
    k++;
  }
  double wall = now_s() - wall0, cpu = cpu_s() - cpu0, p99_all;
  double p99 = worst_window_p99(lat, nlat, (size_t)rate, &p99_all);
  printf("{\"node\": \"sim\", \"steps\": %ld, \"missed_cycles\": %ld, \"late\": %ld, \"stale\": %ld, "
         "\"dropped\": %ld, \"p99_ms\": %.4f, \"p99_all_ms\": %.4f, \"realtime_factor\": %.6f, "
         "\"cpu_per_step_ms\": %.4f, \"slow_state_publishes\": %ld}\n",
         counted, missed, late, stale, dropped, p99, p99_all,
         counted ? (counted + dropped) * T / wall : 0.0, counted ? 1e3 * cpu / counted : 0.0, slow_js);
  fflush(stdout);
  /* let the controller see the end, then go */
  (void)!rcl_subscription_fini(&sub, &r.node);
  (void)!rcl_publisher_fini(&pub_js, &r.node);
  (void)!rcl_publisher_fini(&pub_t, &r.node);
  (void)!rcl_node_fini(&r.node);
  (void)!rcl_shutdown(&r.context);
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}

/* ---------------------------------------------------------------------------------- timer */
/* The floor under the floor: the same absolute 1/RATE deadlines with nothing to do (no ROS, no
 * physics). Counts wake-ups a period or more late and the periods skipped more than 20 behind. */
static int run_timer(double seconds, double rate) {
  double T = 1.0 / rate;
  long n = (long)llround(seconds * rate), warm = (long)llround(rate), late = 0, dropped = 0, counted = 0;
  double *lat = malloc(sizeof(double) * (n + 1)), worst = 0.0;
  long nlat = 0;
  double start = now_s();
  for (long k = 0; k < n && !stop_requested; k++) {
    double due = start + k * T;
    sleep_until(due);
    double behind = now_s() - due;
    if (k < warm) continue;
    if (behind > worst) worst = behind;
    if (behind > 20 * T) { long skip = (long)(behind / T); dropped += skip; k += skip; continue; }
    counted++;
    late += behind >= T;
    lat[nlat++] = 1e3 * behind;
  }
  double p99_all, p99 = worst_window_p99(lat, nlat, (size_t)rate, &p99_all);
  printf("{\"node\": \"timer\", \"steps\": %ld, \"missed_cycles\": %ld, \"late\": %ld, \"dropped\": %ld, "
         "\"wakeup_p99_ms\": %.4f, \"wakeup_p99_all_ms\": %.4f, \"wakeup_max_ms\": %.3f}\n",
         counted, late + dropped, late, dropped, p99, p99_all, 1e3 * worst);
  fflush(stdout);
  return 0;
}

/* ----------------------------------------------------------------------------- controller */
static int run_ctrl(const char *state_topic, const char *command_topic) {
  Ros r;
  ros_init(&r, "floor_controller");
  const rosidl_message_type_support_t *ts_js = ROSIDL_GET_MSG_TYPE_SUPPORT(sensor_msgs, msg, JointState);
  const rosidl_message_type_support_t *ts_arr = ROSIDL_GET_MSG_TYPE_SUPPORT(std_msgs, msg, Float64MultiArray);
  rcl_subscription_t sub = rcl_get_zero_initialized_subscription();
  rcl_subscription_options_t so = rcl_subscription_get_default_options();
  so.qos = stream_qos(1);
  CHECK(rcl_subscription_init(&sub, &r.node, ts_js, state_topic, &so));
  rcl_publisher_t pub = rcl_get_zero_initialized_publisher();
  rcl_publisher_options_t po = rcl_publisher_get_default_options();
  po.qos = stream_qos(100);
  CHECK(rcl_publisher_init(&pub, &r.node, ts_arr, command_topic, &po));
  rcl_wait_set_t ws = rcl_get_zero_initialized_wait_set();
  CHECK(rcl_wait_set_init(&ws, 1, 0, 0, 0, 0, 0, &r.context, rcl_get_default_allocator()));

  sensor_msgs__msg__JointState js;
  sensor_msgs__msg__JointState__init(&js);
  std_msgs__msg__Float64MultiArray cmd;
  array_msg_init(&cmd, "winches");
  size_t cap = 1 << 20, nlat = 0;
  double *lat = malloc(sizeof(double) * cap);
  double last_state = -1.0, cpu0 = cpu_s(), u0[N] = {0};
  int have_u0 = 0;
  long answered = 0, slow_publishes = 0;
  while (!stop_requested) {
    CHECK(rcl_wait_set_clear(&ws));
    CHECK(rcl_wait_set_add_subscription(&ws, &sub, NULL));
    rcl_ret_t rc = rcl_wait(&ws, RCL_MS_TO_NS(100));
    if (rc == RCL_RET_TIMEOUT) {
      if (last_state > 0 && now_s() - last_state > 2.0) break;
      continue;
    }
    if (rc != RCL_RET_OK) continue;
    rmw_message_info_t info;
    int got = 0;
    while (rcl_take(&sub, &js, &info, NULL) == RCL_RET_OK) got = 1;
    if (!got) continue;
    double t_in = now_s();
    size_t n = js.effort.size < N ? js.effort.size : N;
    if (!have_u0) {               /* hold the first state's torques (no random walk of noise) */
      for (size_t i = 0; i < n; i++) u0[i] = js.effort.data[i];
      have_u0 = 1;
    }
    for (size_t i = 0; i < n && i < js.velocity.size; i++)
      cmd.data.data[i] = u0[i] - 0.001 * js.velocity.data[i];
    char label[64];
    snprintf(label, sizeof label, "winches stamp=%.9f", stamp_of(&js.header.stamp));
    rosidl_runtime_c__String__assign(&cmd.layout.dim.data[0].label, label);
    double t_pub = now_s();
    CHECK(rcl_publish(&pub, &cmd, NULL));
    if (now_s() - t_pub > 2e-4) slow_publishes++;   /* held up inside DDS (cablelab's controller_path counts the same) */
    answered++;
    last_state = now_s();
    if (nlat < cap) lat[nlat++] = 1e3 * (last_state - t_in);
  }
  double p99_all, p99 = worst_window_p99(lat, nlat, 1000, &p99_all);
  printf("{\"node\": \"controller\", \"answers\": %ld, \"p99_ms\": %.4f, \"p99_all_ms\": %.4f, "
         "\"cpu_per_answer_ms\": %.4f, \"slow_publishes\": %ld}\n",
         answered, p99, p99_all, answered ? 1e3 * (cpu_s() - cpu0) / answered : 0.0, slow_publishes);
  fflush(stdout);
  (void)!rcl_wait_set_fini(&ws);
  (void)!rcl_subscription_fini(&sub, &r.node);
  (void)!rcl_publisher_fini(&pub, &r.node);
  (void)!rcl_node_fini(&r.node);
  (void)!rcl_shutdown(&r.context);
  return 0;
}

int main(int argc, char **argv) {
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  if (argc >= 6 && strcmp(argv[1], "sim") == 0)
    return run_sim(argv[2], argv[3], atof(argv[4]), atof(argv[5]));
  if (argc >= 2 && strcmp(argv[1], "ctrl") == 0)
    return run_ctrl(argc >= 4 ? argv[2] : "/floor/joint_states", argc >= 4 ? argv[3] : "/floor/effort_commands");
  if (argc >= 4 && strcmp(argv[1], "timer") == 0) return run_timer(atof(argv[2]), atof(argv[3]));
  fprintf(stderr, "usage: floor sim MODEL.mjb STATE.txt SECONDS RATE_HZ | floor ctrl [STATE_TOPIC COMMAND_TOPIC] | "
                  "floor timer SECONDS RATE_HZ\n");
  return 2;
}
