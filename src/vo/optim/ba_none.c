/*
 * Bundle adjustment when mvod is built without Ceres: absent, so vo.c runs two-view mode
 * where map mode is asked for (mvod_vo_run_mode); the calls answer -ENOTSUP (test_ba.c skips).
 */
#include "ba_shim.h"

#include <errno.h>
#include <stddef.h>

const bool mvod_ba_present = false;

int mvod_ba_create(struct mvod_ba **out)
{
	*out = NULL;
	return -ENOTSUP;
}

int mvod_ba_solve(struct mvod_ba *ba, const struct mvod_ba_problem *p,
		  const struct mvod_ba_options *o, struct mvod_ba_result *r)
{
	return -ENOTSUP;
}

void mvod_ba_destroy(struct mvod_ba *ba)
{
}

int mvod_ba_jacobian_mismatches(const double pose[6], const double X[3],
				const struct mvod_ba_obs *o, double fx, double fy, double cx,
				double cy, bool *evaluated)
{
	*evaluated = false;
	return -ENOTSUP;
}
