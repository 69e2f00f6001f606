/* The backends' path helper (errors: util/errbuf.h). */
#ifndef MVOD_CAPTURE_PATH_H
#define MVOD_CAPTURE_PATH_H

#include <stddef.h>

/* "dir/name" into buf; -ENAMETOOLONG with the reason in err when it does not fit. */
int mvod_capture_path(char *buf, size_t len, const char *dir, const char *name, char *err,
		      size_t errlen);

#endif
