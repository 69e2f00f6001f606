/* The libcamera door of a build without libcamera: the scheme is known, and says so. */
#include "capture/libcamera_shim.h"

#include <errno.h>

#include "util/errbuf.h"

int mvod_lcam_open(const struct mvod_lcam_want *want, struct mvod_lcam **out,
		   struct mvod_lcam_mode *mode, char *err, size_t errlen)
{
	return mvod_errf(err, errlen, -ENOTSUP, "%s", MVOD_LCAM_NOT_BUILT);
}

int mvod_lcam_wait(struct mvod_lcam *c, int timeout_ms, struct mvod_lcam_frame *f)
{
	return -ENODEV;
}

int mvod_lcam_release(struct mvod_lcam *c)
{
	return 0;
}

void mvod_lcam_close(struct mvod_lcam *c)
{
}

int mvod_lcam_list(FILE *out)
{
	return -ENOTSUP;
}
