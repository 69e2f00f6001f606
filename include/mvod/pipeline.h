/* The run loop: source -> vo -> sinks, shared by the daemon and the in-process tests. */
#ifndef MVOD_PIPELINE_H
#define MVOD_PIPELINE_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>

#include "mvod/capture.h"
#include "mvod/eval.h"
#include "mvod/ipc.h"
#include "mvod/sink.h"
#include "mvod/traj.h"
#include "mvod/status.h"
#include "mvod/vo.h"

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_run_opts {
	const char *source;     /* URI */
	const char *calib;      /* file, or NULL when the source carries intrinsics */
	const char *gt;         /* ground-truth trajectory, or NULL */
	const char *trajectory; /* output, or NULL */
	enum mvod_traj_format traj_format;
	const char *plot;       /* PNG, or NULL */
	int64_t max_frames;     /* 0 = all */
	int require_gt;         /* a frame without a ground-truth pose is an error (as --scale gt) */
	/*
	 * The caller's own sinks (mvod bench's pose collector), borrowed, after the evaluation
	 * and before the built-in outputs; ops->destroy is not called. NULL when n_sinks is 0.
	 */
	const struct mvod_sink *sinks;
	int n_sinks;
	double status_hz;       /* periodic mvod.status_t (and systemd STATUS=) rate. 1 */
	/* Set (by SIGHUP) to have the run reopen its trajectory by name; cleared when done. */
	volatile sig_atomic_t *reopen;
	enum mvod_axes axes;           /* camera */
	const char *camera_to_body;    /* "x,y,z,qx,qy,qz,qw" with axes ros, or NULL */
	enum mvod_clock clock;         /* monotonic; realtime only for live cameras */
	struct mvod_vo_params vo;
	/*
	 * --scale external: where mvod.speed_t comes from (an LCM URL, "" for LCM's default, or
	 * file://LOG), NULL = none given; and its channel (MVOD_SPEED).
	 */
	const char *speed_url;
	const char *speed_channel;
};
void mvod_run_opts_default(struct mvod_run_opts *o);

/*
 * Runs to the end of the source, max_frames, or until *stop becomes non-zero. ipc may be NULL
 * (no publishing). Returns 0 or -errno; setup errors are logged with what to do about them.
 */
int mvod_run(const struct mvod_run_opts *opts, struct mvod_ipc *ipc, volatile sig_atomic_t *stop,
	     struct mvod_run_summary *summary);

#ifdef __cplusplus
}
#endif

#endif
