/* One-line error reasons handed back to the caller, who logs them with context. */
#ifndef MVOD_ERRBUF_H
#define MVOD_ERRBUF_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Room for a reason: two paths of any length (a file and the folder it names) and the words
 * around them. 512 bytes cut the reason off a path of 450 characters.
 */
#define MVOD_ERR_MAX (2 * 4096 + 512)

/*
 * Formats the reason into err (when err is non-NULL and errlen > 0), control characters as
 * spaces, and returns code.
 */
int mvod_errf(char *err, size_t errlen, int code, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));

#ifdef __cplusplus
}
#endif

#endif
