/*
 * What a run reports, apart from the run loop itself (mvod/pipeline.h): the daemon's state and
 * its status message, the summary of a finished run, the output poses' frame and the frame
 * times' clock. The sinks, LCM and mvod view take these types without the pipeline; the names
 * are src/util/status.c's.
 */
#ifndef MVOD_STATUS_H
#define MVOD_STATUS_H

#include <stdbool.h>
#include <stdint.h>

#include "mvod/capture.h"
#include "mvod/eval.h"
#include "mvod/vo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The daemon's state, as status messages and mvod view report it: while frames flow, the VO's
 * tracking state (the same values), around that the daemon's own. Values are mvod.pose_t's
 * and mvod.status_t's STATE_ constants (pinned in src/ipc/ipc.c).
 */
enum mvod_run_state {
	MVOD_RUN_STARTING = 0, /* before the first frame */
	MVOD_RUN_INITIALIZING = MVOD_STATE_INITIALIZING,
	MVOD_RUN_TRACKING = MVOD_STATE_TRACKING,
	MVOD_RUN_LOST = MVOD_STATE_LOST,
	MVOD_RUN_SOURCE_DOWN = 4, /* a live source went away; the capture thread reopens it */
	MVOD_RUN_STOPPING = 5,    /* the last status of a run */
	/*
	 * A state byte no value above (a newer sender's, a corrupt log) as a message reader
	 * takes it (mvod_run_state_from_wire): loading the byte itself into the enum is undefined
	 * in C++ (mvod view's drawing; UBSan's -fsanitize=enum).
	 */
	MVOD_RUN_UNKNOWN = -1,
};
const char *mvod_run_state_name(enum mvod_run_state s);

/* What mvod.status_t carries: the daemon's health, published by the run, shown by mvod view. */
struct mvod_status {
	int64_t utime;   /* source clock of the last frame, microseconds */
	double fps;      /* frames processed per wall-clock second */
	double stage_ms[MVOD_STAGE_COUNT]; /* mean per-stage milliseconds */
	int features, matches, inliers; /* of the last frame */
	int64_t frames, dropped;
	int64_t rss_kb;
	double uptime_s;
	enum mvod_run_state state;
	int32_t faults; /* mvod.status_t FAULT_ bits */
	int map_points, keyframes; /* map mode's map, of the last frame (0 in two-view mode) */
	double scale;              /* metres per output unit, 0 when unknown */
	double scale_confidence;   /* 0-1 */
	double latency_ms;         /* capture to publish of the last frame, milliseconds */
};

/* The frame of the poses mvod outputs (LCM, trajectory): --frame. */
enum mvod_axes {
	MVOD_AXES_CAMERA = 0, /* the camera's optical frame: x right, y down, z forward */
	MVOD_AXES_ROS = 1,    /* a body frame, ROS REP 103: x forward, y left, z up */
};
extern const char *const mvod_axes_names[]; /* "camera", "ros", NULL */

/* The clock of live cameras' frame times (utime): --clock. */
enum mvod_clock {
	MVOD_CLOCK_MONOTONIC = 0, /* CLOCK_MONOTONIC, as the driver stamps the buffer */
	MVOD_CLOCK_REALTIME = 1,  /* the same instant on CLOCK_REALTIME (Unix time) */
};
extern const char *const mvod_clock_names[]; /* "monotonic", "realtime", NULL */

/* Summary of a finished run (printed by the daemon, asserted by tests). */
struct mvod_run_summary {
	int64_t frames, tracked, held;
	/*
	 * The run did not start because of its camera model: the calibration is missing,
	 * unreadable, malformed, of another image size, or absent where the source has none.
	 */
	bool calib_failed;
	/*
	 * The run did not start because of its configuration: anything that failed after the
	 * source opened and before the first frame but memory (the calibration, the ground
	 * truth, --scale's height or speed, --frame, the front end for the image size, an output
	 * the policy refuses). An edit fixes it, a restart does not (the daemon's exit status 2).
	 */
	bool config_failed;
	const char *frontend; /* the front end that ran, by mvod_vo_frontend_name: klt, orb, sift */
	bool live;       /* frames came through the capture thread */
	/* frames a live source produced that were not processed, the skipped ones apart */
	int64_t dropped;
	/* frames skipped because they could not be decoded, by mvod_bad_frame reason */
	int64_t skipped[MVOD_BAD_COUNT];
	double wall_s, fps;
	double stage_ms_mean[MVOD_STAGE_COUNT];
	double stage_ms_max[MVOD_STAGE_COUNT];
	double frame_ms_median, frame_ms_p95; /* whole frame, within 1 % (a log histogram) */
	/* with ground truth */
	int have_gt;         /* some frames had a ground-truth pose */
	int64_t gt_frames;   /* how many; the accuracy is over these */
	int64_t gt_first, gt_last; /* index of the first and the last of them; -1 without */
	int gt_static;       /* every ground-truth pose within 1 mm of the first: no ATE */
	double est_len, est_extent; /* the estimate's path length and farthest point from its
				       start, in its own units (metres with --scale gt) */
	double ate_rmse_m;   /* after SE(3) (gt scale) or Sim(3) (auto scale) alignment; NAN
				when none exists (static ground truth, or an estimate that does not move) */
	double ate_scale;    /* the alignment's scale: estimate units to metres (1 for SE(3)) */
	double path_len_m;   /* ground-truth path length */
	struct mvod_rpe rpe;
};

#ifdef __cplusplus
}
#endif

#endif
