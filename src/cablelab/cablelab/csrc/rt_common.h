/* What the compiled per-period paths share: the monotonic clock, absolute-deadline sleep and the
 * QoS of the project's streams (cablelab/ros/qos.py: reliable, keep-last depth; transient local
 * where the Python publisher is). Header-only: each path is its own shared library. */
#ifndef CABLELAB_RT_COMMON_H
#define CABLELAB_RT_COMMON_H

#include <errno.h>
#include <rmw/qos_profiles.h>
#include <time.h>

/* seconds of CLOCK_MONOTONIC (Python's time.monotonic) */
static inline double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* sleep to now_s() == t with clock_nanosleep's absolute mode (no drift, a signal resumes it) */
static inline void sleep_until(double t) {
  struct timespec ts;
  ts.tv_sec = (time_t)t;
  ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
  if (ts.tv_nsec >= 1000000000L) { ts.tv_sec += 1; ts.tv_nsec -= 1000000000L; }
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {}
}

/* reliable, keep-last `depth`, transient local or volatile */
static inline rmw_qos_profile_t qos(size_t depth, int transient_local) {
  rmw_qos_profile_t q = rmw_qos_profile_default;
  q.history = RMW_QOS_POLICY_HISTORY_KEEP_LAST;
  q.depth = depth;
  q.reliability = RMW_QOS_POLICY_RELIABILITY_RELIABLE;
  q.durability = transient_local ? RMW_QOS_POLICY_DURABILITY_TRANSIENT_LOCAL : RMW_QOS_POLICY_DURABILITY_VOLATILE;
  return q;
}

#endif
