/* What the evaluation sink keeps, for the plot sink that draws it (both in src/sink/). */
#ifndef MVOD_SINK_EVAL_SINK_H
#define MVOD_SINK_EVAL_SINK_H

#include "mvod/eval.h"
#include "mvod/sink.h"

struct mvod_sink_eval {
	bool sim3;                       /* free scale: align by Sim(3), else SE(3) */
	struct mvod_path est_path, gt_path; /* bounded: longer runs are decimated, never grown */
	struct mvod_path est_at_gt;      /* the estimate at the frames gt_path has: the ATE's pairs */
	int64_t gt_frames, gt_first, gt_last; /* frames with a ground-truth pose, first and last */
	struct mvod_pose prev_est, prev_gt;
	bool have_prev, prev_had_gt; /* a frame has been recorded; it had a ground-truth pose */
	struct mvod_rpe rpe;
	/*
	 * Free scale: each pair's error terms, so that err_avg is computed again at the end in
	 * metres, on the estimate scaled by the ATE's alignment, as mvod bench does. Allocated at
	 * create for max_pairs; pairs beyond are counted in lost_pairs.
	 */
	struct mvod_frame_err *pairs;
	int n_pairs, max_pairs, lost_pairs;
	double path_len_m;           /* ground-truth path length */
	bool aligned;                /* est_path was Sim(3)-aligned to the ground truth */
	double heading[9];           /* the last estimated orientation, aligned as est_path */
};

#endif
