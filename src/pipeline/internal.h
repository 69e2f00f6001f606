/*
 * What the files of the run loop share (src/pipeline/): the run's state, and the steps one
 * file takes for another. Private to src/pipeline/.
 */
#ifndef MVOD_PIPELINE_INTERNAL_H
#define MVOD_PIPELINE_INTERNAL_H

#include <limits.h>
#include <stdbool.h>
#include <stdint.h>

#include "mvod/pipeline.h"
#include "mvod/speed.h"
#include "mvod/status.h"
#include "util/body_frame.h"

/* The built-in sinks (eval, notify, LCM, plot, trajectory) and the caller's. */
#define MAX_SINKS 16

/*
 * Frame times go into a fixed histogram of 1 % wide logarithmic bins from 0.01 ms to ~80 s, so
 * a daemon running for months keeps its median and 95th percentile in constant memory.
 */
#define FT_BINS 1600
#define FT_MIN_MS 0.01
#define FT_GROWTH 1.01

struct run {
	const struct mvod_run_opts *o;
	struct mvod_source *src;
	struct mvod_source_info info;
	struct mvod_camera cam;
	struct mvod_traj gt;
	char gt_from[PATH_MAX]; /* the ground truth's file: --gt, or the one the dataset carries */
	bool gt_from_source;    /* the dataset's: frames before it begins are skipped when needed */
	int64_t skipped_lead;   /* frames skipped so */
	struct mvod_vo *vo;
	struct mvod_body_frame body; /* --frame, --camera-to-body: the output poses' frame */
	double latency_ms;           /* of the last frame: delivered by the source to published */
	struct mvod_ipc *ipc;
	struct mvod_sink sinks[MAX_SINKS]; /* in the order they are called */
	bool owned[MAX_SINKS];             /* made here: destroyed here */
	int n_sinks;
	struct mvod_run_summary *sum;
	double stage_total[MVOD_STAGE_COUNT];
	uint32_t frame_hist[FT_BINS];
	double t_start, last_status;
	enum mvod_run_state state;
	struct mvod_frame last_frame;      /* for status messages sent between frames */
	struct mvod_vo_result last_res;
	struct mvod_capture *cap;          /* live sources: their capture thread */
	int epoch;                         /* times the live source came back */
	int64_t last_index;                /* of the last frame processed, -1 before */
	bool restarted;                    /* the VO forgot the scene before the next frame */
	/* mvod.status_t FAULT_ bits seen so far; status_due: publish status with the next frame */
	struct mvod_faults faults;
	struct mvod_speed *speed;          /* --scale external */
	bool speed_stale;                  /* the last frame had no speed near its time */
	struct mvod_speed_counts speed_refused; /* refused messages already logged */
};

/* Opens the source, its camera and ground truth, the scale's sources and the VO; logs why not. */
int mvod_run_open_inputs(struct run *r);
/* Opens every output (after the inputs: bad input leaves no output behind). */
int mvod_run_open_outputs(struct run *r);
/* Each sink's hook, in order; frame and finish return the first error. */
int mvod_run_sinks_frame(struct run *r, const struct mvod_frame_out *f);
void mvod_run_sinks_status(struct run *r, const struct mvod_status *st, bool news);
void mvod_run_sinks_between(struct run *r, bool reopen);
int mvod_run_sinks_finish(struct run *r);
void mvod_run_sinks_destroy(struct run *r);
/* Frame f's ground-truth pose, or NULL. */
const struct mvod_pose *mvod_run_gt_for(const struct run *r, const struct mvod_frame *f);
/* Whether f comes before the ground truth the dataset carries begins (then skipped). */
bool mvod_run_before_gt(struct run *r, const struct mvod_frame *f);
/* Logs why f has no ground-truth pose, for a run that needs one for every frame. */
void mvod_run_log_missing_gt(const struct run *r, const struct mvod_frame *f);
/* --scale external: the odometer at f's time into the VO. */
void mvod_run_feed_speed(struct run *r, const struct mvod_frame *f);
/* A frame's counts, times and state change; returns its milliseconds. */
double mvod_run_record(struct run *r, const struct mvod_frame *f, const struct mvod_vo_result *res);
/* Whether the periodic status is due. */
bool mvod_run_status_due(const struct run *r);
/* The status of frame f (res) to every sink. */
void mvod_run_publish_status(struct run *r, const struct mvod_frame *f,
			     const struct mvod_vo_result *res);
/* The summary's times and rates at the end of the run. */
void mvod_run_summarise(struct run *r);

#endif
