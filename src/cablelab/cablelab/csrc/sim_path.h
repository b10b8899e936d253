/* The CDPR simulator's compiled per-period path (sim_path.c): its counters, read by Python
 * (cablelab.plants.cdpr.sim_path) in this order. */
#ifndef CABLELAB_SIM_PATH_H
#define CABLELAB_SIM_PATH_H

#include <stdint.h>
#include <mujoco/mujoco.h>

#define SP_MAX_N 64 /* winches */

enum {
  SP_STEPS,             /* steps computed */
  SP_COMMANDS,          /* good commands taken */
  SP_REJECTED,          /* commands rejected (empty, wrong length, NaN) */
  SP_LAST_PROBLEM,      /* the last rejection: SP_PROBLEM_* */
  SP_LAST_BAD_LENGTH,   /* ... its value count */
  SP_LAST_GOOD_NS,      /* CLOCK_MONOTONIC ns of the last good command */
  SP_FALLBACKS,         /* steps on the brakes */
  SP_FALLBACKS_RUNNING, /* ... after the first command */
  SP_SLACK,             /* steps ending with a slack cable */
  SP_LATE,              /* steps run a period or more after they were due */
  SP_DROPPED,           /* steps dropped (more than 20 behind) */
  SP_STALE,             /* steps whose command answers an older state */
  SP_MISSED,            /* steps late, braked or stale (each once) */
  SP_AGE1, SP_AGE2, SP_AGE3, /* steps whose command answers the state 1, 2, >= 3 periods back */
  SP_MASS_CHANGED,      /* the scheduled payload was put on */
  SP_DONE,              /* the duration was reached */
  SP_RING_LOST,         /* samples the Python side did not drain in time (not published) */
  SP_PUBLISH_ERRORS,
  SP_SLOW_JS, SP_SLOW_TEN, SP_SLOW_REF, /* publishes of the joint states, tensions, reference over
                                           0.2 ms, once commands came */
  SP_PUBLISH_MAX_NS,    /* ... the slowest publish, ns */
  SP_WAKE_MAX_NS,       /* the latest wake-up after a deadline, ns, once commands came */
  SP_NCOUNTS
};

enum { SP_PROBLEM_NONE, SP_PROBLEM_EMPTY, SP_PROBLEM_LENGTH, SP_PROBLEM_NAN };

typedef struct SimPath SimPath;

long sp_stride(const mjModel *m);

#endif
