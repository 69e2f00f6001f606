/* Shared by the integration and data tests: run the real binaries, make temp dirs, compare. */
#ifndef MVOD_TEST_HARNESS_H
#define MVOD_TEST_HARNESS_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

#include "mvod/eval.h"
#include "mvod/traj.h"
#include "mvod_pose2_t.h"
#include "mvod_pose_t.h"
#include "mvod_status2_t.h"
#include "mvod_status_t.h"

/* Exit code meson reads as "skipped". */
#define EXIT_SKIP 77

struct run_result {
	int exited;   /* 1 when the process exited (not killed by a signal) */
	int status;   /* exit status, or the signal number */
	char out[16384];
	char err[16384];
};

/* Runs argv (NULL-terminated) and captures stdout and stderr. Returns 0 or -errno. */
int harness_run(char *const argv[], struct run_result *r);
/* Path of a binary from the environment (MVOD, MVOD_SYNTH), failing the test if unset. */
const char *harness_bin(const char *env);
/* mvod_source_open(uri) fails with code, no source, and an err holding needle. */
void harness_source_open_fails(const char *uri, int code, const char *needle);
/* Writes text to path, failing the test if it cannot. */
void harness_write_file(const char *path, const char *text);
/* Reads at most len - 1 bytes of path into buf, NUL-terminated; "" when it cannot be read. */
void harness_read_file(const char *path, char *buf, size_t len);
/* The whole of dir/name, malloc'd and NUL-terminated, its length in *len; missing: fails. */
char *harness_slurp(const char *dir, const char *name, size_t *len);
/* A fresh temporary directory, removed by harness_cleanup(). */
const char *harness_tmpdir(void);
/* meson install of the build tree into the DESTDIR root, without a rebuild; a failure fails. */
void harness_meson_install(const char *root);
/* "TMPDIR/name" in one of 8 static buffers, reused in turn (so 8 may be held at once). */
const char *harness_tmp_path(const char *name);
void harness_cleanup(void);
/* A cmocka group teardown that calls harness_cleanup(). */
int harness_teardown(void **state);
/* Starts argv in the background, stdout and stderr into files (NULL: /dev/null). */
pid_t harness_spawn(char *const argv[], const char *out_path, const char *err_path);
/*
 * Waits until pid is mvod (harness_bin("MVOD"): not the forked test before exec, which still
 * holds the test's descriptors) and holds path open; fails the test if pid ends first.
 */
void harness_wait_open(pid_t pid, const char *path);
/* Waits for pid; 1 with its exit status in *status, or 0 with the signal that killed it. */
int harness_wait(pid_t pid, int *status);
/*
 * Runs argv with stdout on a pipe whose reader is closed before it starts, so every write to
 * stdout fails with EPIPE, and stderr into err_path; returns as harness_wait.
 */
int harness_run_reader_gone(char *const argv[], const char *err_path, int *status);
/*
 * Poses in a trajectory file, failing the test unless every line parses and every line is a
 * pose (no half-written line at the end).
 */
int harness_traj_lines(const char *path);
/* Complete lines in a file, or -1 when it cannot be read. */
int harness_count_lines(const char *path);
/* Waits until path has at least n lines, failing the test if pid ends first. */
void harness_wait_lines(const char *path, int n, pid_t pid);

/*
 * Starts argv (NULL-terminated; output not captured), sends it sig once path holds at least
 * lines lines, and returns its wait status; fails the test if it ends before.
 */
int harness_signal_after(char *const argv[], const char *path, int lines, int sig);
/* Replaces frame i (w x h) of a PNG sequence in images/ with a black P5 PGM: no features. */
void harness_blacken(const char *images, int i, int w, int h);
/* Renders a sequence with mvod-synth into dir; then extra arguments, NULL-terminated. */
void harness_synth(const char *dir, const char *path_name, int frames, const char *format, ...);

/* Errors of an estimated trajectory against ground truth, frame by frame (same count). */
struct traj_errors {
	int n;
	struct mvod_rpe rpe;
	double ate_m;     /* after alignment; +inf when none exists (a motionless estimate) */
	double scale;     /* similarity scale of the alignment (1 for SE(3)) */
	double length_m;  /* ground-truth path length */
	double max_translation; /* largest |t| of the estimate (drift of a static camera) */
	double scale_drift; /* mvod_scale_drift: largest over smallest 20-step window scale; NAN if undefined */
};
void harness_compare(const char *est_path, const char *gt_path, int sim3, struct traj_errors *e);

/* What a file:// LCM log written by mvod holds, on the default channels. */
struct log_contents {
	int poses, statuses;
	int poses2, statuses2; /* mvod.pose2_t, status2_t on MVOD_POSE2, MVOD_STATUS2 */
	int bad;            /* events that do not decode */
	int gaps;           /* poses not numbered one after the last (frames skipped before) */
	int64_t last_frame; /* of the last pose, -1 without one */
	mvod_status_t last_status;
};
/* Reads the whole log (failing the test if it cannot be opened); on_status may be NULL. */
void harness_read_log(const char *path, struct log_contents *c,
		      void (*on_status)(const mvod_status_t *msg, void *ctx), void *ctx);
/*
 * The mvod.pose_t or mvod.status_t messages of such a log (read as harness_read_log does,
 * failing the test if any message does not decode): how many, the first max of them into out.
 */
int harness_poses(const char *log, mvod_pose_t *out, int max);
int harness_statuses(const char *log, mvod_status_t *out, int max);
/* The same for mvod.pose2_t and mvod.status2_t. */
int harness_poses2(const char *log, mvod_pose2_t *out, int max);
int harness_statuses2(const char *log, mvod_status2_t *out, int max);

#endif
