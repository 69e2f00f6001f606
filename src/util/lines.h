/*
 * The one reader of line-oriented text files (times.txt, dataset indexes, ground truth and
 * trajectories, KITTI calib.txt, TUM camera.txt, bench's rows): the file opened through the
 * input path (util/input.h: noted as an input, a regular file only, at most
 * MVOD_LINES_MAX_BYTES), read through one buffer of MVOD_LINE_MAX bytes allocated at open.
 * A line that does not fit, or a byte no text holds (NUL, control characters other than tab,
 * CR, LF, VT, FF), is an error naming the file and the line, never an early end of the file.
 *
 *   struct mvod_lines *l;
 *   char *line;
 *   size_t n;
 *   int ret = mvod_lines_open(path, "TUM rgb.txt", &l, err, errlen);
 *   while (!ret && (ret = mvod_lines_next(l, &line, &n, err, errlen)) > 0)
 *           ...;                       // line: NUL-terminated, its end cut off, borrowed
 *   mvod_lines_close(l);               // ret: 0 at the end, or -errno with err filled
 *
 * or mvod_lines_each(path, what, fn, ctx, err, errlen), which skips blank and '#' lines.
 */
#ifndef MVOD_LINES_H
#define MVOD_LINES_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Bytes a line may take, its end included: twice PATH_MAX, so an index line naming any path
 * fits; the longest line of any format mvod reads (a KITTI pose, 12 numbers) is ~200.
 */
#define MVOD_LINE_MAX 8192
/* A day of 100 Hz TUM poses is ~860 MB: beyond 1 GiB a line file is no input of mvod's. */
#define MVOD_LINES_MAX_BYTES ((size_t)1 << 30)

struct mvod_lines;

/*
 * Opens path, the `what` of messages ("ground truth", "EuRoC data.csv"), through the input
 * path. Returns 0 with *out, or -errno with a one-line reason in err (-ENOENT when there is
 * no such file, -EISDIR, -EINVAL for a FIFO or device, -EFBIG).
 */
int mvod_lines_open(const char *path, const char *what, struct mvod_lines **out, char *err,
		    size_t errlen);
/*
 * The next line: 1 with *line (NUL-terminated, "\n" or "\r\n" cut off, a UTF-8 byte order
 * mark before the first cut too; valid until the next call) and its number from 1 in
 * *lineno; 0 at the end of the file; -errno with a reason naming path and line: -E2BIG for a
 * line of MVOD_LINE_MAX bytes or more, -EILSEQ for a byte that is not text, -EFBIG, -errno.
 */
int mvod_lines_next(struct mvod_lines *l, char **line, size_t *lineno, char *err,
		    size_t errlen);
/* Closes and frees; NULL is a no-op. */
void mvod_lines_close(struct mvod_lines *l);

/*
 * One line for mvod_lines_each; ctx is the caller's. Returns 0 to go on, > 0 to stop reading
 * there (no error), or -errno with a reason in err, which ends the reading with that error.
 */
typedef int (*mvod_line_fn)(void *ctx, char *line, size_t lineno, char *err, size_t errlen);

/*
 * Reads path line by line and hands fn each line that is not blank or a '#' comment.
 * Returns 0, fn's error, or mvod_lines_open's and mvod_lines_next's.
 */
int mvod_lines_each(const char *path, const char *what, mvod_line_fn fn, void *ctx, char *err,
		    size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
