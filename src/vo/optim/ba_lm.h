/*
 * Map mode's windowed bundle adjustment (ba.h's problem), solved by a Levenberg-Marquardt
 * written for its window (at most 64 poses) on buffers allocated at create time (ba_lm.c says
 * what of Ceres it follows; tests/unit/test_ba.c compares the two). Plain C.
 */
#ifndef MVOD_BA_LM_H
#define MVOD_BA_LM_H

#include "ba.h"

struct mvod_ba_lm;

/* Buffers for problems of up to these sizes (pose_cap <= 64). -EINVAL, -ENOMEM. */
int mvod_ba_lm_create(int pose_cap, int point_cap, int obs_cap, struct mvod_ba_lm **out);
void mvod_ba_lm_destroy(struct mvod_ba_lm *b);
/*
 * As mvod_ba_solve: p solved in place, observations behind their camera before solving
 * flagged and left out, those above chi2_outlier after it flagged. -EINVAL for a problem
 * larger than the buffers, a point observed more than 64 times, an index out of range or a
 * sigma <= 0.
 */
int mvod_ba_lm_solve(struct mvod_ba_lm *b, const struct mvod_ba_problem *p,
		     const struct mvod_ba_options *o, struct mvod_ba_result *r);

#endif
