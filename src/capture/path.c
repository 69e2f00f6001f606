#include "capture/path.h"

#include <errno.h>
#include <stdio.h>

#include "util/errbuf.h"

int mvod_capture_path(char *buf, size_t len, const char *dir, const char *name, char *err,
		      size_t errlen)
{
	int n = snprintf(buf, len, "%s/%s", dir, name);
	if (n < 0 || (size_t)n >= len)
		return mvod_errf(err, errlen, -ENAMETOOLONG, "path too long: %s/%s", dir,
					 name);
	return 0;
}
