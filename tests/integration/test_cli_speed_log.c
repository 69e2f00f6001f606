/*
 * mvod speed-log, a user tool (the speed-log maker was a test binary that `make demo` did not
 * build, while the README's --scale external recipe called it): its log holds exactly the
 * speed of a ground truth, TUM or KITTI with --times; its refusals each say what to do, exit
 * 2 and leave an existing OUT as it was; OUT is never an input.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>
#include <lcm/eventlog.h>

#include "harness.h"
#include "mvod_speed_t.h"

/* Three poses of a KITTI file: 3 m then 4 m along x (times 0, 0.5, 1.5 s). */
#define KITTI_POSES                                                                               \
	"1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 3 0 1 0 0 0 0 1 0\n1 0 0 7 0 1 0 0 0 0 1 0\n"
/* The same path in TUM, at times 10, 10.5, 11.5 s. */
#define TUM_POSES "10 0 0 0 0 0 0 1\n10.5 3 0 0 0 0 0 1\n11.5 7 0 0 0 0 0 1\n"

static struct run_result r;

/* mvod speed-log with args (NULL-terminated), expecting exit code and needle in its output. */
static void speed_log(int code, const char *needle, ...)
{
	char *argv[24] = {(char *)harness_bin("MVOD"), "speed-log"};
	int n = 2;
	va_list ap;
	va_start(ap, needle);
	for (char *a; n < 23 && (a = va_arg(ap, char *));)
		argv[n++] = a;
	va_end(ap);
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != code || !strstr(code ? r.err : r.out, needle))
		fail_msg("expected exit %d and \"%s\", got %d: %s%s", code, needle, r.status, r.out,
			 r.err);
}

/* The log's messages: their count, and each one's event time equal to its utime. */
static int read_log(const char *path, mvod_speed_t *m, int max, const char *channel)
{
	lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
	assert_non_null(log);
	int n = 0;
	lcm_eventlog_event_t *ev;
	while ((ev = lcm_eventlog_read_next_event(log))) {
		assert_true(n < max);
		assert_string_equal(ev->channel, channel);
		assert_true(mvod_speed_t_decode(ev->data, 0, ev->datalen, &m[n]) > 0);
		assert_int_equal(ev->timestamp, m[n].utime);
		n++;
		lcm_eventlog_free_event(ev);
	}
	lcm_eventlog_destroy(log);
	return n;
}

/* Exactly the path's speed: 3 m in 0.5 s, then 4 m in 1 s, odometer 3 then 7 m. */
static void expect_path(const char *path, int64_t t0_us, const char *channel, bool distance)
{
	mvod_speed_t m[4];
	assert_int_equal(read_log(path, m, 4, channel), 2);
	assert_int_equal(m[0].utime, t0_us + 500000);
	assert_int_equal(m[1].utime, t0_us + 1500000);
	assert_true(m[0].speed == 6.0 && m[1].speed == 4.0);
	assert_int_equal(m[0].has_distance, distance);
	assert_true(m[0].distance == 3.0 && m[1].distance == 7.0);
}

/* The path as TUM and KITTI, KITTI's times (times_text) and an OUT, named NAME.* in the tmp dir. */
struct inputs {
	char tum[300], kitti[300], times[300], out[300];
};

static void write_inputs(struct inputs *in, const char *name, const char *times_text)
{
	const char *dir = harness_tmpdir();
	snprintf(in->tum, sizeof(in->tum), "%s/%s.tum", dir, name);
	snprintf(in->kitti, sizeof(in->kitti), "%s/%s.kitti", dir, name);
	snprintf(in->times, sizeof(in->times), "%s/%s.times.txt", dir, name);
	snprintf(in->out, sizeof(in->out), "%s/%s.lcmlog", dir, name);
	harness_write_file(in->tum, TUM_POSES);
	harness_write_file(in->kitti, KITTI_POSES);
	harness_write_file(in->times, times_text);
}

static void test_tum_and_kitti(void **state)
{
	(void)state;
	struct inputs in;
	write_inputs(&in, "gt", "0.0\n0.5\n1.5\n");
	const char *tum = in.tum, *kitti = in.kitti, *times = in.times, *out = in.out;
	char want[600];
	snprintf(want, sizeof(want), "mvod speed-log: wrote 2 mvod.speed_t on MVOD_SPEED to %s, "
		 "10.500 s to 11.500 s\n", out);
	speed_log(0, want, tum, out, NULL);
	assert_string_equal(r.out, want);
	expect_path(out, 10000000, "MVOD_SPEED", true);
	speed_log(0, "wrote 2", kitti, out, "--times", times, "--channel", "ODOM", "--no-distance",
		  NULL);
	expect_path(out, 0, "ODOM", false);
	/*
	 * --bias scales every step: 2 % more (4.08 m/s, 7.14 m, to within the rounding of the
	 * products, 1e-12). --from and --samples keep a part.
	 */
	speed_log(0, "wrote 1", tum, out, "--bias", "0.02", "--from", "1", NULL);
	mvod_speed_t m[4];
	assert_int_equal(read_log(out, m, 4, "MVOD_SPEED"), 1);
	assert_true(fabs(m[0].speed - 4.08) < 1e-12 && fabs(m[0].distance - 7.14) < 1e-12);
	speed_log(0, "", tum, out, "--samples", "1", "-q", NULL);
	assert_string_equal(r.out, ""); /* -q: nothing but errors */
	assert_int_equal(read_log(out, m, 4, "MVOD_SPEED"), 1);
	assert_true(m[0].speed == 6.0);
}

/* Each refusal: exit 2, what to do, and the OUT of the run before left as it was. */
static void test_refusals(void **state)
{
	(void)state;
	struct inputs in;
	write_inputs(&in, "r", "0.0\n0.5\n"); /* a time short */
	const char *tum = in.tum, *kitti = in.kitti, *times = in.times, *out = in.out;
	harness_write_file(out, "the run before");
	speed_log(2, "is KITTI: its poses carry no times: pass the sequence's --times times.txt",
		  kitti, out, NULL);
	speed_log(2, "2 times for the 3 poses of", kitti, out, "--times", times, NULL);
	speed_log(2, "is TUM: it has its own times: drop --times", tum, out, "--times", times, NULL);
	speed_log(2, "and --samples and --from leave none", tum, out, "--from", "2", NULL);
	speed_log(2, "--noise 2: expected a number in [0, 1]", tum, out, "--noise", "2", NULL);
	speed_log(2, "expected GT and OUT.lcmlog", tum, NULL);
	speed_log(2, "is a directory", tum, harness_tmpdir(), NULL);
	char text[64];
	harness_read_file(out, text, sizeof(text));
	assert_string_equal(text, "the run before");
	/* The ground truth is an input: never written over. */
	speed_log(2, "mvod never writes over its input", tum, tum, NULL);
	harness_read_file(tum, text, sizeof(text));
	assert_int_equal(strncmp(text, "10 0 0 0", 8), 0);
	speed_log(0, "Usage: mvod speed-log GT OUT.lcmlog", "--help", NULL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_tum_and_kitti),
		cmocka_unit_test(test_refusals),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
