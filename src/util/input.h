/*
 * The one way mvod opens a file it reads (configuration, calibration, ground truth, dataset
 * indexes and frames, LCM logs): the file is noted as an input, so no output of the process
 * may be it (util/output.h); its type is checked before a byte is read, so a FIFO nobody
 * writes into, /dev/zero or a folder never hangs or floods a reader; its size is bounded.
 */
#ifndef MVOD_INPUT_H
#define MVOD_INPUT_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

#ifdef __cplusplus
extern "C" {
#endif

/* How mvod_input_open takes a file: flags, or'ed. */
enum {
	/*
	 * A FIFO or pipe a process writes into is taken besides a regular file (a --config or
	 * --calib given as <(command)); one nobody writes into is refused at once. Without this
	 * flag, only a regular file is: a FIFO, a device or a socket is refused.
	 */
	MVOD_INPUT_STREAM = 1 << 0,
	/* Noted as an input already (the frames a source listed at start): not again, so that
	 * a frame's open allocates nothing. */
	MVOD_INPUT_NOTED = 1 << 1,
};

/* An open input; the strings are borrowed and must outlive it. */
struct mvod_input {
	int fd;
	bool fifo;         /* a FIFO or pipe: its first read tells whether a process writes */
	bool first;        /* no byte read yet */
	size_t got, max;   /* bytes read so far; the bound */
	off_t size;        /* a regular file's size at open, -1 for a stream */
	const char *path, *what;
};

/*
 * Opens path, the `what` of the message ("ground truth", "EuRoC data.csv"), for reading:
 * noted as an input (unless MVOD_INPUT_NOTED), then refused with a one-line reason naming
 * path and what: -ENOENT (no such file), -EISDIR (a folder), -EINVAL (a FIFO, device or
 * socket where a regular file is meant), -EFBIG (a regular file over max bytes), -errno.
 * Never blocks. Returns 0, with in filled; mvod_input_close releases it.
 */
int mvod_input_open(struct mvod_input *in, const char *path, const char *what, int flags,
		    size_t max, char *err, size_t errlen);
/*
 * Reads up to len bytes (retrying after signals): how many, 0 at the end, or -errno with a
 * reason naming the file: -ENXIO for a FIFO that no process writes into, -EFBIG once a
 * stream passes max bytes.
 */
ssize_t mvod_input_read(struct mvod_input *in, void *buf, size_t len, char *err, size_t errlen);
/* Closes the file; in may be closed twice (the second is a no-op). */
void mvod_input_close(struct mvod_input *in);

#ifdef __cplusplus
}
#endif

#endif
