/*
 * mvod view on damaged LCM logs (issue 10): an absurd event length must not crash it (LCM's
 * own reader would), a log corrupt in the middle is refused with the place, and a log cut
 * short at its end (a writer stopped mid-event) plays up to there and says so.
 */
#include <fcntl.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#define FRAMES 6
#define MAX_EVENTS 64

static char log_path[300];
static long offsets[MAX_EVENTS + 1]; /* where each event starts; then the end of the log */
static int events;

static uint32_t be32(const unsigned char *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* The event offsets of the log, from its 28-byte headers (see src/view/lcmlog.c). */
static void index_log(void)
{
	FILE *f = fopen(log_path, "rb");
	assert_non_null(f);
	unsigned char h[28];
	long off = 0;
	for (events = 0; events < MAX_EVENTS && fread(h, 1, 28, f) == 28; events++) {
		offsets[events] = off;
		off += 28 + (long)be32(h + 20) + (long)be32(h + 24);
		assert_int_equal(fseek(f, off, SEEK_SET), 0);
	}
	offsets[events] = off;
	fclose(f);
	assert_true(events > FRAMES); /* a pose per frame, and status */
}

static int setup(void **state)
{
	(void)state;
	char seq[256], video[300], calib[300], url[400];
	snprintf(seq, sizeof(seq), "%s/seq", harness_tmpdir());
	harness_synth(seq, "forward", FRAMES, "mkv", "--size", "320x240", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", seq);
	snprintf(calib, sizeof(calib), "%s/calib.json", seq);
	snprintf(log_path, sizeof(log_path), "%s/run.lcmlog", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s?mode=w", log_path);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib,
			"--lcm-url", url, "-q", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mvod failed: %s", r.err);
	index_log();
	return 0;
}

/* A copy of the log, changed by patch (at offset, len bytes) and cut to size (<0: whole). */
static void damaged_copy(const char *path, long offset, const void *patch, size_t len, long size)
{
	char cmd[800];
	snprintf(cmd, sizeof(cmd), "cp '%s' '%s'", log_path, path);
	assert_int_equal(system(cmd), 0);
	int fd = open(path, O_WRONLY);
	assert_true(fd >= 0);
	if (patch)
		assert_int_equal(pwrite(fd, patch, len, offset), (ssize_t)len);
	if (size >= 0)
		assert_int_equal(ftruncate(fd, size), 0);
	close(fd);
}

static void view(const char *path, struct run_result *r)
{
	char url[400], png[300];
	snprintf(url, sizeof(url), "file://%s?mode=r&speed=0", path);
	snprintf(png, sizeof(png), "%s/view.png", harness_tmpdir());
	char *argv[] = {(char *)harness_bin("MVOD"), "view", "--lcm-url", url, "--png", png, NULL};
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited)
		fail_msg("mvod view killed by signal %d: %s", r->status, r->err);
}

/* The third event's data length set to 2^31 - 1: refused with the place, no crash. */
static void test_absurd_length(void **state)
{
	(void)state;
	char path[300], want[200];
	snprintf(path, sizeof(path), "%s/absurd.lcmlog", harness_tmpdir());
	static const unsigned char len[4] = {0x7f, 0xff, 0xff, 0xff};
	damaged_copy(path, offsets[2] + 24, len, 4, -1);
	struct run_result r;
	view(path, &r);
	snprintf(want, sizeof(want), "is corrupt at byte %ld of %ld: event of", offsets[2],
		 offsets[events]);
	if (r.status != 1 || !strstr(r.err, want) ||
	    !strstr(r.err, "runs past the end of the log") || !strstr(r.err, "the 2 events"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* A sync word overwritten mid-log: refused with the place, not shown as a clean end. */
static void test_corrupt_middle(void **state)
{
	(void)state;
	char path[300], want[200];
	snprintf(path, sizeof(path), "%s/middle.lcmlog", harness_tmpdir());
	damaged_copy(path, offsets[3], "\0\0\0\0", 4, -1);
	struct run_result r;
	view(path, &r);
	snprintf(want, sizeof(want), "is corrupt at byte %ld of %ld: no event starts here",
		 offsets[3], offsets[events]);
	if (r.status != 1 || !strstr(r.err, want) || strstr(r.out, "end of log"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* The last event cut in half: the events before it play, and the summary says where it ends. */
static void test_cut_tail(void **state)
{
	(void)state;
	char path[300], want[200];
	snprintf(path, sizeof(path), "%s/cut.lcmlog", harness_tmpdir());
	long last = offsets[events - 1];
	damaged_copy(path, 0, NULL, 0, last + (offsets[events] - last) / 2);
	struct run_result r;
	view(path, &r);
	snprintf(want, sizeof(want), "(end of log, cut short at byte %ld)", last);
	if (r.status != 0 || !strstr(r.out, want) || !strstr(r.err, "is cut short at byte"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* The log as mvod wrote it: no warning, a clean end. */
static void test_sound_log(void **state)
{
	(void)state;
	struct run_result r;
	view(log_path, &r);
	if (r.status != 0 || !strstr(r.out, "(end of log)\n") || r.err[0])
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* No log, or an empty one: said so, where LCM would only ask to check --lcm-url. */
static void test_missing_and_empty(void **state)
{
	(void)state;
	char path[300];
	struct run_result r;
	snprintf(path, sizeof(path), "%s/none.lcmlog", harness_tmpdir());
	view(path, &r);
	if (r.status != 1 || !strstr(r.err, "none.lcmlog: No such file or directory") ||
	    strstr(r.err, "check --lcm-url"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
	snprintf(path, sizeof(path), "%s/empty.lcmlog", harness_tmpdir());
	harness_write_file(path, "");
	view(path, &r);
	if (r.status != 1 || !strstr(r.err, "empty.lcmlog holds no whole event (0 bytes)") ||
	    strstr(r.err, "check --lcm-url"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_absurd_length),
		cmocka_unit_test(test_corrupt_middle),
		cmocka_unit_test(test_cut_tail),
		cmocka_unit_test(test_sound_log),
		cmocka_unit_test(test_missing_and_empty),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
