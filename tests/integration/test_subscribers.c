/*
 * The installed subscriber bindings, as a user on the robot meets them: `meson install` into a
 * DESTDIR; the C and C++ examples (their installed sources) built against the installed
 * mvod-lcmtypes.pc only (PKG_CONFIG_PATH and PKG_CONFIG_SYSROOT_DIR into the root, never the
 * build tree) and run against the installed library; each reads a file:// log mvod wrote for a
 * short mvod-synth clip and prints every pose and status exactly as decoded here, matching the
 * trajectory file too; fault bits and states decode to their names; the installed fingerprints
 * are those the messages carry. With --python, the Python example on the same input instead
 * (exit 77 when Python's lcm module cannot be imported: Debian 12 ships none).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>
#include <lcm/eventlog.h>
#include <lcm/lcm.h>

#include "harness.h"
#include "mvod/traj.h"

/* Enough frames for mvod to initialise and track; small ones: mvod-synth renders them fast. */
#define FRAMES 12
#define MAX_MSGS 64

static char root[256];   /* the DESTDIR */
static char prefix[512]; /* root + the build's prefix */
static char log_path[300], faults_log[300], traj_path[300];
static char pkg_env[1400]; /* the environment pkg-config runs in */

/* Runs a shell command line, failing the test with its output unless it exits 0. */
static void shell(const char *what, const char *cmd, struct run_result *r)
{
	char *argv[] = {"/bin/sh", "-c", (char *)cmd, NULL};
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited || r->status != 0)
		fail_msg("%s: exit %d\n%s\n%s%s", what, r->status, cmd, r->out, r->err);
}

static void run_mvod(void)
{
	char dir[300], video[320], calib[320], url[400];
	snprintf(dir, sizeof(dir), "%s/seq", harness_tmpdir());
	harness_synth(dir, "forward", FRAMES, "mkv", "--size", "320x240", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(log_path, sizeof(log_path), "%s/mvod.lcmlog", harness_tmpdir());
	snprintf(traj_path, sizeof(traj_path), "%s/trajectory.tum", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s?mode=w", log_path);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib,
			"--lcm-url", url, "--trajectory", traj_path, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mvod failed: %s", r.err);
}

/*
 * Status messages with every fault bit, one bit newer than the bindings, and unknown states;
 * the v2 type's new fields with values a float and a %.6g print exactly.
 */
static const mvod_status2_t fault_statuses[] = {
	{.utime = 1, .frames = 1, .state = MVOD_POSE_T_STATE_TRACKING, .faults = 0,
	 .map_points = 1200, .keyframes = 7, .scale = 0.25, .latency_ms = 4.5},
	{.utime = 2, .frames = 2, .state = MVOD_POSE_T_STATE_LOST, .faults = 15},
	{.utime = 3, .frames = 3, .state = MVOD_POSE_T_STATE_SOURCE_DOWN, .faults = 4 | 256},
	{.utime = 4, .frames = 4, .state = 9, .faults = INT32_MIN},
	{.utime = 5, .frames = 5, .state = MVOD_POSE_T_STATE_STOPPING, .faults = 8},
};
#define V2_ZERO " map_points=0 keyframes=0 scale=0 latency_ms=0.000\n"
static const char fault_lines[] =
	"status utime=1 frames=1 state=TRACKING faults=none map_points=1200 keyframes=7 "
	"scale=0.25 latency_ms=4.500\n"
	"status utime=2 frames=2 state=LOST "
	"faults=TRAJECTORY_WRITE|FRAME_UNREADABLE|SOURCE_BROKEN|PUBLISH" V2_ZERO
	"status utime=3 frames=3 state=SOURCE_DOWN faults=SOURCE_BROKEN|0x100" V2_ZERO
	"status utime=4 frames=4 state=9 faults=0x80000000" V2_ZERO
	"status utime=5 frames=5 state=STOPPING faults=PUBLISH" V2_ZERO;

static void write_fault_log(void)
{
	char url[400];
	snprintf(faults_log, sizeof(faults_log), "%s/faults.lcmlog", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s?mode=w", faults_log);
	lcm_t *lcm = lcm_create(url);
	assert_non_null(lcm);
	for (size_t i = 0; i < sizeof(fault_statuses) / sizeof(fault_statuses[0]); i++)
		assert_int_equal(mvod_status2_t_publish(lcm, "MVOD_STATUS2", &fault_statuses[i]), 0);
	lcm_destroy(lcm);
}

static int setup(void **state)
{
	(void)state;
	snprintf(root, sizeof(root), "%s/root", harness_tmpdir());
	harness_meson_install(root);
	snprintf(prefix, sizeof(prefix), "%s%s", root, harness_bin("MVOD_PREFIX"));
	snprintf(pkg_env, sizeof(pkg_env),
		 "PKG_CONFIG_PATH=%s/%s/pkgconfig PKG_CONFIG_SYSROOT_DIR=%s "
		 "LD_LIBRARY_PATH=%s/%s",
		 prefix, harness_bin("MVOD_LIBDIR"), root, prefix, harness_bin("MVOD_LIBDIR"));
	run_mvod();
	write_fault_log();
	return 0;
}

/* pkg-config's flags point into the root, not at the build tree nor the system. */
static void test_pkg_config_points_into_destdir(void **state)
{
	(void)state;
	char cmd[2048];
	struct run_result r;
	snprintf(cmd, sizeof(cmd), "export %s; pkg-config --cflags --libs mvod-lcmtypes", pkg_env);
	shell("pkg-config", cmd, &r);
	char want[600];
	snprintf(want, sizeof(want), "-I%s/include/mvod-lcmtypes", prefix);
	if (!strstr(r.out, want) || !strstr(r.out, "-lmvod-lcmtypes") || !strstr(r.out, "-llcm"))
		fail_msg("pkg-config says \"%s\", wants %s, -lmvod-lcmtypes, -llcm", r.out, want);
	if (strstr(r.out, harness_bin("MVOD_BUILDDIR")))
		fail_msg("pkg-config names the build tree: %s", r.out);
}

/* Every installed fingerprint is the one mvod's messages of that type start with. */
static void test_fingerprints(void **state)
{
	(void)state;
	char path[700], text[1024];
	snprintf(path, sizeof(path), "%s/%s/mvod/lcmtypes/fingerprints.txt", prefix,
		 harness_bin("MVOD_DATADIR"));
	harness_read_file(path, text, sizeof(text));
	lcm_eventlog_t *ev = lcm_eventlog_create(log_path, "r");
	assert_non_null(ev);
	/* Each channel's type, by the channel's name. */
	static const char *const channels[] = {"MVOD_STATUS", "MVOD_POSE", "MVOD_STATUS2",
					       "MVOD_POSE2"};
	static const char *const types[] = {"status_t", "pose_t", "status2_t", "pose2_t"};
	int checked[4] = {0, 0, 0, 0};
	lcm_eventlog_event_t *e;
	while ((e = lcm_eventlog_read_next_event(ev))) {
		int k = 0;
		while (k < 4 && strcmp(e->channel, channels[k]) != 0)
			k++;
		assert_true(k < 4);
		char line[80];
		const unsigned char *d = e->data;
		uint64_t fp = 0;
		for (int i = 0; i < 8 && e->datalen >= 8; i++)
			fp = fp << 8 | d[i];
		snprintf(line, sizeof(line), "\nmvod.%s 0x%016llx\n", types[k], (unsigned long long)fp);
		if (!strstr(text, line))
			fail_msg("%s (a message on %s) is not in %s:\n%s", line + 1, e->channel, path,
				 text);
		checked[k]++;
		lcm_eventlog_free_event(e);
	}
	lcm_eventlog_destroy(ev);
	assert_int_equal(checked[1], FRAMES);
	assert_int_equal(checked[3], FRAMES);
	assert_true(checked[0] >= 1);
	assert_int_equal(checked[2], checked[0]);
}

/* The lines a subscriber prints for the messages of the log mvod wrote. */
static void expected_lines(char *buf, size_t len)
{
	static mvod_pose2_t p[MAX_MSGS];
	static mvod_status2_t s[MAX_MSGS];
	int np = harness_poses2(log_path, p, MAX_MSGS);
	int ns = harness_statuses2(log_path, s, MAX_MSGS);
	assert_int_equal(np, FRAMES);
	assert_true(ns >= 1 && ns <= MAX_MSGS);
	static const char *const states[] = {"STARTING", "INITIALIZING", "TRACKING", "LOST",
					     "SOURCE_DOWN", "STOPPING"};
	size_t n = 0;
	for (int i = 0; i < np && n < len; i++) {
		assert_in_range(p[i].state, 0, 5);
		n += (size_t)snprintf(buf + n, len - n,
				      "pose frame=%lld utime=%lld position=%.6f,%.6f,%.6f "
				      "orientation=%.6f,%.6f,%.6f,%.6f state=%s quality=%.3f "
				      "keyframe=%d\n",
				      (long long)p[i].frame, (long long)p[i].utime,
				      p[i].position[0], p[i].position[1], p[i].position[2],
				      p[i].orientation[0], p[i].orientation[1],
				      p[i].orientation[2], p[i].orientation[3], states[p[i].state],
				      p[i].quality, p[i].keyframe);
	}
	/* mvod sets no fault on a clean run. */
	for (int i = 0; i < ns && n < len; i++) {
		assert_int_equal(s[i].faults, 0);
		assert_in_range(s[i].state, 0, 5);
		n += (size_t)snprintf(buf + n, len - n,
				      "status utime=%lld frames=%lld state=%s faults=none "
				      "map_points=%d keyframes=%d scale=%.6g latency_ms=%.3f\n",
				      (long long)s[i].utime, (long long)s[i].frames,
				      states[s[i].state], s[i].map_points, s[i].keyframes,
				      s[i].scale, s[i].latency_ms);
	}
	assert_true(n < len);
}

/* The lines of text that begin with start, in order, into out. */
static void only_lines(const char *text, const char *start, char *out, size_t len)
{
	size_t n = 0;
	out[0] = '\0';
	for (const char *l = text; *l;) {
		const char *end = strchr(l, '\n');
		size_t k = end ? (size_t)(end - l) + 1 : strlen(l);
		if (strncmp(l, start, strlen(start)) == 0 && n + k < len) {
			memcpy(out + n, l, k);
			out[n += k] = '\0';
		}
		l += k;
	}
}

/* Each pose printed is the trajectory line of its frame: time and position. */
static void check_against_trajectory(const char *out)
{
	struct mvod_traj t;
	char err[512];
	if (mvod_traj_load(traj_path, &t, err, sizeof(err)))
		fail_msg("%s", err);
	assert_int_equal(t.n, FRAMES);
	const char *l = out;
	for (int i = 0; i < t.n; i++) {
		long long frame, utime;
		double x, y, z;
		l = strstr(l, "pose ");
		assert_non_null(l);
		assert_int_equal(sscanf(l, "pose frame=%lld utime=%lld position=%lf,%lf,%lf", &frame,
					&utime, &x, &y, &z), 5);
		assert_int_equal(frame, i);
		/* TUM times are printed to the microsecond: equal after rounding. */
		assert_int_equal(utime, llround(t.t[i] * 1e6));
		/* 5e-7 from printing %.6f, and the TUM file's 9 significant digits. */
		assert_float_equal(x, t.pose[i].t[0], 1e-6);
		assert_float_equal(y, t.pose[i].t[1], 1e-6);
		assert_float_equal(z, t.pose[i].t[2], 1e-6);
		l++;
	}
	mvod_traj_free(&t);
}

/* Runs a built subscriber (a command line ending in the program) on a log; its stdout. */
static void subscribe(const char *program, const char *log, char *out, size_t len)
{
	char cmd[2400], out_path[300];
	snprintf(out_path, sizeof(out_path), "%s/subscriber.out", harness_tmpdir());
	snprintf(cmd, sizeof(cmd), "export %s; %s 'file://%s?mode=r&speed=0' >%s", pkg_env,
		 program, log, out_path);
	struct run_result r;
	shell(program, cmd, &r);
	/* Nothing on stderr: LCM's decoders say there when a message does not decode. */
	if (r.err[0])
		fail_msg("%s: %s", program, r.err);
	harness_read_file(out_path, out, len);
}

/* The example's output for mvod's log and for the log of faults. */
static void check_subscriber(const char *program)
{
	static char out[65536], want[65536], got[65536], want_part[65536];
	subscribe(program, log_path, out, sizeof(out));
	expected_lines(want, sizeof(want));
	const char *kinds[] = {"pose ", "status "};
	for (int k = 0; k < 2; k++) {
		only_lines(out, kinds[k], got, sizeof(got));
		only_lines(want, kinds[k], want_part, sizeof(want_part));
		assert_string_equal(got, want_part);
	}
	check_against_trajectory(out);
	subscribe(program, faults_log, out, sizeof(out));
	assert_string_equal(out, fault_lines);
}

/*
 * Builds an installed example with the compiler and flags given, against mvod-lcmtypes.pc
 * only, and checks what it prints.
 */
static void check_example(const char *compiler, const char *flags, const char *source)
{
	char cmd[4096], san[128] = "", program[300];
	const char *sanitize = harness_bin("MVOD_SANITIZE");
	if (strcmp(sanitize, "none") != 0) /* the installed library was built with it */
		snprintf(san, sizeof(san), "-fsanitize=%s", sanitize);
	snprintf(program, sizeof(program), "%s/%s.exe", harness_tmpdir(), source);
	snprintf(cmd, sizeof(cmd),
		 "export %s; %s %s %s -Wall -Wextra -Wno-unused-parameter -Werror "
		 "%s/%s/mvod/examples/%s $(pkg-config --cflags --libs mvod-lcmtypes) -o %s",
		 pkg_env, harness_bin(compiler), flags, san, prefix, harness_bin("MVOD_DATADIR"),
		 source, program);
	struct run_result r;
	shell(source, cmd, &r);
	check_subscriber(program);
}

static void test_c_example(void **state)
{
	(void)state;
	check_example("MVOD_CC", "-std=c11", "subscribe.c");
}

static void test_cpp_example(void **state)
{
	(void)state;
	check_example("MVOD_CXX", "-std=c++11", "subscribe.cpp");
}

/* The package from pkg-config's pythondir (which pkgconf prefixes with the sysroot too). */
static void test_python_example(void **state)
{
	(void)state;
	char program[1400];
	snprintf(program, sizeof(program),
		 "PYTHONPATH=$(pkg-config --variable=pythondir mvod-lcmtypes) python3 "
		 "%s/%s/mvod/examples/subscribe.py",
		 prefix, harness_bin("MVOD_DATADIR"));
	check_subscriber(program);
}

int main(int argc, char **argv)
{
	if (argc > 1 && strcmp(argv[1], "--python") == 0) {
		if (system("python3 -c 'import lcm' 2>/dev/null") != 0) {
			fprintf(stderr, "python3 cannot import lcm (pip install lcm): skipped\n");
			return EXIT_SKIP;
		}
		const struct CMUnitTest tests[] = {cmocka_unit_test(test_python_example)};
		return cmocka_run_group_tests(tests, setup, harness_teardown);
	}
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_pkg_config_points_into_destdir),
		cmocka_unit_test(test_fingerprints),
		cmocka_unit_test(test_c_example),
		cmocka_unit_test(test_cpp_example),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
