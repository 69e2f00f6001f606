/* Whole small input files (configuration, calibration) read at once, with a size bound. */
#ifndef MVOD_READ_FILE_H
#define MVOD_READ_FILE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Reads the file at path through the input path (util/input.h; flags as mvod_input_open's:
 * MVOD_INPUT_STREAM takes a FIFO a process writes into) into a NUL-terminated malloc'ed *out
 * (the caller frees it), its length without the NUL into *len (may be NULL). A file longer
 * than max bytes is no `what` (e.g. "config file"): -EFBIG. Returns 0 or -errno with a
 * one-line reason naming path.
 */
int mvod_read_file(const char *path, size_t max, const char *what, int flags, char **out,
		   size_t *len, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
