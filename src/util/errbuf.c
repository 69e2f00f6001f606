#include "util/errbuf.h"

#include <stdarg.h>
#include <stdio.h>

int mvod_errf(char *err, size_t errlen, int code, const char *fmt, ...)
{
	if (err && errlen) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(err, errlen, fmt, ap);
		va_end(ap);
		/*
		 * Reasons quote the input they reject (a JSON excerpt, a URI, a board spec), which
		 * may hold line breaks: as spaces, the reason stays one line in the log.
		 */
		for (char *c = err; *c; c++)
			if ((unsigned char)*c < 0x20 || *c == 0x7f)
				*c = ' ';
	}
	return code;
}
