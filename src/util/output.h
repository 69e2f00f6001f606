/*
 * The one output policy for every file mvod writes (trajectory, LCM log, calibration, board,
 * reports, plots, tables):
 *   - a symlink is followed to its target, which is what gets written (the link stays a link);
 *   - a regular file (or nothing) is replaced by temp+rename, or appended to by a stream;
 *   - a character device or a FIFO is written into, never replaced; a FIFO is opened without
 *     blocking, so one that no process reads is refused at once instead of hanging mvod;
 *   - a directory, a block device or a socket is refused;
 *   - a file this process reads (an input noted below: source, frames, times.txt, calibration,
 *     ground truth, configuration) is refused, compared by device and inode, before any output
 *     is opened;
 *   - a stream output (trajectory, file:// LCM log) is locked with flock, so a second mvod on
 *     the same file is refused, and is truncated only when its first record is written, so a
 *     start that fails leaves the file of the run before as it was.
 */
#ifndef MVOD_OUTPUT_H
#define MVOD_OUTPUT_H

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Notes path (followed through symlinks) as an input of this process by device and inode, and
 * its name, so that a file which later takes the inode of a deleted input is not taken for it.
 * A path that does not exist is no input: 0. Returns 0 or -errno (-ENOMEM). Thread-safe.
 */
int mvod_input_note(const char *path);
/*
 * Forgets path (followed through symlinks) as an input: for the one command that updates a
 * file it read, whole, by temp+rename (mvod mount's camera file), after it has read it.
 */
void mvod_input_release(const char *path);
/* Forgets every input noted (tests; a process ends without it). */
void mvod_inputs_forget(void);

enum mvod_output_kind {
	MVOD_OUTPUT_NEW,     /* nothing there yet: created */
	MVOD_OUTPUT_REGULAR, /* a regular file: replaced or truncated */
	MVOD_OUTPUT_DEVICE,  /* a character device: written into */
	MVOD_OUTPUT_FIFO,    /* a FIFO: written into, opened without blocking */
};

/*
 * Applies the policy to path before anything is opened: follows symlinks (up to 40) into
 * target (the file that will be written; targetlen >= 2 bytes), says what is there in *kind
 * (may be NULL), and refuses, with a one-line reason in err naming what (e.g. "--trajectory"):
 * a directory (-EISDIR), a block device or socket (-EPERM), an input noted above (-EEXIST),
 * a folder that cannot be written in (-errno). Returns 0 or -errno.
 */
int mvod_output_check(const char *what, const char *path, char *target, size_t targetlen,
		      enum mvod_output_kind *kind, char *err, size_t errlen);

/* A stream output: records appended one write(2) each (trajectory lines, LCM log events). */
struct mvod_output;

/*
 * Checks path as above, opens it and locks it: -EWOULDBLOCK with a reason when another
 * process holds it, -ENXIO when it is a FIFO nobody reads. A regular file is truncated at
 * the first mvod_output_write, not here. Returns 0 or -errno with a reason in err.
 */
int mvod_output_open(const char *what, const char *path, struct mvod_output **out, char *err,
		     size_t errlen);
/*
 * Writes one record with one write(2): a killed process never leaves part of one. A short
 * write (full disk) is cut back, so the file ends with whole records. Returns 0 or -errno;
 * the first error is kept and returned again by mvod_output_close. No allocation.
 */
int mvod_output_write(struct mvod_output *o, const void *buf, size_t len);
/*
 * Log rotation: opens the path again through the policy (created, or appended to when it
 * exists, and locked); the old file is fsynced and closed. On failure the old file stays in
 * use. Returns 0 or -errno with a reason in err.
 */
int mvod_output_reopen(struct mvod_output *o, char *err, size_t errlen);
/* fsyncs (where the file can be) and closes; the first error of any write or this. NULL: 0. */
int mvod_output_close(struct mvod_output *o);
/*
 * Whether a stream output is open: a signal handler may call it (it reads one sig_atomic_t).
 * mvod run's stop handler ends a start-up at once while none is, with nothing to close.
 */
bool mvod_outputs_open(void);

#ifdef __cplusplus
}
#endif

#endif
