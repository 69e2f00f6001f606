/* Output files that appear whole under their name or not at all. */
#ifndef MVOD_ATOMIC_FILE_H
#define MVOD_ATOMIC_FILE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Writes buf to "DIR/.NAME.tmp-PID-N" beside path, fsyncs it and renames it over path, so a
 * crash, a full disk or a power cut leaves the old file or the new one, never half of one.
 * The file is created 0666 less the umask. Returns 0 or -errno; the temporary never remains.
 */
int mvod_write_replace(const char *path, const void *buf, size_t len);

#ifdef __cplusplus
}
#endif

#endif
