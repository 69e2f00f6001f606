/* Output files that appear whole under their name or not at all. */
#ifndef MVOD_ATOMIC_FILE_H
#define MVOD_ATOMIC_FILE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Writes buf to path through the output policy (util/output.h). A symlink is followed and its
 * target written, the link left as it is. A regular file, or nothing, is replaced: buf goes
 * to "DIR/.NAME.tmp-PID-N" beside the target, is fsynced and renamed over it, so a crash, a
 * full disk or a power cut leaves the old file or the new one, never half of one; the new
 * file keeps the old one's permissions, or is created 0666 less the umask. A character device
 * or a FIFO (which must have a reader: -ENXIO) is written into, never replaced. A directory
 * (-EISDIR), a block device or socket (-EPERM) or an input of this process (-EEXIST) is
 * refused. Returns 0 or -errno; the temporary never remains.
 */
int mvod_write_replace(const char *path, const void *buf, size_t len);

#ifdef __cplusplus
}
#endif

#endif
