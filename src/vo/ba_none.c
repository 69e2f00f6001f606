/* Bundle adjustment when mvod is built without Ceres: map mode learns it at create. */
#include "ba_shim.h"

#include <errno.h>
#include <stddef.h>

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
