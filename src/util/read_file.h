/* Whole small input files (configuration, calibration) read at once, with a size bound. */
#ifndef MVOD_READ_FILE_H
#define MVOD_READ_FILE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Reads the file at path into a NUL-terminated malloc'ed *out (the caller frees it), its
 * length without the NUL into *len (may be NULL). A file longer than max bytes is no `what`
 * (e.g. "config file"): -EFBIG. Returns 0 or -errno with a one-line reason naming path.
 */
int mvod_read_file(const char *path, size_t max, const char *what, char **out, size_t *len, char *err,
		   size_t errlen);

/*
 * One line of a text file, its end ("\n" or "\r\n") cut off, lineno from 1; ctx is the
 * caller's. Returns 0 to go on, > 0 to stop reading there (no error), or -errno with a reason
 * in err, which ends the reading with that error.
 */
typedef int (*mvod_line_fn)(void *ctx, char *line, size_t lineno, char *err, size_t errlen);

/*
 * Reads the text file at path line by line (indexes, timestamps, trajectories: inputs of any
 * length), skipping blank lines and '#' comments, and hands the rest to fn. path is noted as
 * an input (util/output.h). Returns 0, fn's error, or -errno with a one-line reason naming
 * path in err (-ENOENT when it does not exist; -EISDIR for a directory).
 */
int mvod_read_lines(const char *path, mvod_line_fn fn, void *ctx, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
