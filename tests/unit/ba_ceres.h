/*
 * Ceres Solver on map mode's bundle adjustment problem (src/vo/optim/ba.h): the reference
 * tests/unit/test_ba.c compares ba_lm.c with, built where Ceres is installed (meson defines
 * MVOD_HAVE_CERES then); mvod itself never links Ceres.
 */
#ifndef MVOD_TESTS_BA_CERES_H
#define MVOD_TESTS_BA_CERES_H

#include <errno.h>
#include <stdbool.h>

#include "vo/optim/ba.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifdef MVOD_HAVE_CERES
static const bool ba_ceres_present = true;
/*
 * Solves p in place as ba_lm.c does (DENSE_SCHUR, Huber's loss, Jacobi scaling; its options'
 * iterations and function tolerance), with AutoDiff's Jacobians. An observation whose point is
 * behind its camera before solving is flagged and left out. -EINVAL for an index out of range
 * or a sigma <= 0; -EIO when Ceres fails.
 */
int ba_ceres_solve(const struct mvod_ba_problem *p, const struct mvod_ba_options *o,
		   struct mvod_ba_result *r);
#else
static const bool ba_ceres_present = false;
static inline int ba_ceres_solve(const struct mvod_ba_problem *p,
				 const struct mvod_ba_options *o, struct mvod_ba_result *r)
{
	*r = (struct mvod_ba_result){0};
	return -ENOTSUP;
}
#endif

#ifdef __cplusplus
}
#endif

#endif
