/*
 * Where the run loop's results go. A sink is a const struct mvod_sink_ops and its state, the
 * way a source is a mvod_source_ops: LCM (pose and status messages), the trajectory file,
 * systemd notifications, the evaluation against ground truth, the --plot PNG, and any caller's
 * per-frame hook (mvod bench collects its poses through one). The run calls every sink's
 * hooks in the order the sinks were given; a hook left NULL is skipped.
 */
#ifndef MVOD_SINK_H
#define MVOD_SINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mvod/capture.h"
#include "mvod/ipc.h"
#include "mvod/traj.h"
#include "mvod/vo.h"

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_run_summary;

/* One processed frame, as sinks see it; every pointer is borrowed for the call only. */
struct mvod_frame_out {
	const struct mvod_frame *frame;
	const struct mvod_vo_result *res; /* res->pose: the camera's, for the evaluation */
	const struct mvod_pose *pose; /* what LCM and the trajectory get: in --frame's axes */
	const struct mvod_pose *gt; /* ground-truth pose of this frame, or NULL */
	double frame_ms;            /* capture and every VO stage */
	bool restarted;             /* the VO forgot the scene before this frame (source came back) */
};

/*
 * The run's fault bits (mvod.status_t FAULT_*), shared with the sinks. mvod_faults_set returns
 * true the first time a bit is set, when the caller logs the fault; later occurrences show only
 * in status, so a fault that repeats every frame does not flood the log. A new fault makes
 * status due at once.
 */
struct mvod_faults {
	int32_t bits;
	bool status_due;
};
bool mvod_faults_set(struct mvod_faults *f, int32_t bit);

struct mvod_sink_ops {
	const char *name;
	/* After each frame. A negative errno ends the run with it (after the other sinks ran). */
	int (*frame)(void *ctx, const struct mvod_frame_out *f);
	/* A status report: news (a state change, a fault, the last one) or periodic. */
	void (*status)(void *ctx, const struct mvod_status *st, bool news);
	/* Between frames, also while a live source is down; reopen: SIGHUP asked to reopen files. */
	void (*between)(void *ctx, bool reopen);
	/*
	 * Once, after the last frame and the last status; summary is complete except for what
	 * earlier sinks' finish adds (evaluation before plot). 0 or -errno, logged by the sink.
	 */
	int (*finish)(void *ctx, struct mvod_run_summary *summary);
	void (*destroy)(void *ctx);
};

struct mvod_sink {
	const struct mvod_sink_ops *ops;
	void *ctx; /* owned by the sink when ops->destroy is set, else borrowed */
};

/*
 * The built-in sinks, each created before the first frame (all their memory allocated here)
 * and destroyed through ops->destroy. faults is borrowed and outlives the sink.
 */
/* Poses and status over LCM; ipc is borrowed. */
int mvod_sink_lcm_create(struct mvod_ipc *ipc, struct mvod_faults *faults, struct mvod_sink *out);
/*
 * Every pose to path, one whole line each, through the output policy (util/output.h); the
 * file is closed in finish. A refusal says why in err.
 */
int mvod_sink_traj_create(const char *path, enum mvod_traj_format fmt,
			  struct mvod_faults *faults, struct mvod_sink *out, char *err,
			  size_t errlen);
/* systemd: READY after the first frame, WATCHDOG between frames, STATUS, STOPPING. */
int mvod_sink_notify_create(struct mvod_sink *out);

/*
 * Evaluation against ground truth: the paths, RPE, ground-truth path length, and at finish the
 * ATE after an SE(3) (sim3 false) or Sim(3) alignment, into the summary. With sim3, err_avg
 * and err_max are computed at finish on the estimate scaled by the alignment (as mvod bench
 * does); gt_poses, the ground truth's pose count, sizes what that keeps.
 */
int mvod_sink_eval_create(bool sim3, int gt_poses, struct mvod_sink *out);
/*
 * The --plot PNG of the evaluation's paths, written at finish; eval is borrowed. A path whose
 * extension names no image format (mvod_plot_check) is refused here, before the first frame.
 */
int mvod_sink_plot_create(const char *path, const char *source, bool gt_scale,
			  const struct mvod_sink *eval, struct mvod_sink *out);

#ifdef __cplusplus
}
#endif

#endif
