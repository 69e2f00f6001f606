/* The viewer's state: heading, pose rate, fixed memory, newest state, and the panel's rows. */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "mvod/plot.h"
#include "mvod/view.h"
#include "mvod_pose2_t.h"
#include "mvod_pose_t.h"
#include "mvod_status2_t.h"
#include "mvod_status_t.h"

static mvod_pose_t pose_at(double z, double yaw_deg)
{
	/* A turn about the y axis (down): +yaw swings forward (+z) towards +x. */
	double h = yaw_deg * M_PI / 360.0;
	return (mvod_pose_t){.position = {0, 0, z}, .orientation = {cos(h), 0, sin(h), 0},
			     .state = MVOD_POSE_T_STATE_TRACKING};
}

static const char *value_of(const struct mvod_view_row *rows, int n, const char *label)
{
	for (int i = 0; i < n; i++)
		if (strcmp(rows[i].label, label) == 0)
			return rows[i].value;
	fail_msg("no row '%s'", label);
	return NULL;
}

static void test_yaw(void **state)
{
	(void)state;
	struct mvod_view v;
	assert_int_equal(mvod_view_init(&v, 100), 0);
	assert_true(isnan(mvod_view_yaw_deg(&v)));
	static const double yaws[] = {0, 30, -90, 179.5, 180};
	for (size_t i = 0; i < sizeof(yaws) / sizeof(yaws[0]); i++) {
		mvod_pose_t p = pose_at(0, yaws[i]);
		mvod_view_add_pose(&v, &p, 0);
		/* Through a quaternion and atan2: exact to rounding. */
		assert_true(fabs(mvod_view_yaw_deg(&v) - yaws[i]) < 1e-9);
	}
	/* Looking straight down (pitch 90 deg about x): no heading on the ground plane. */
	mvod_pose_t down = {.orientation = {cos(M_PI / 4), sin(M_PI / 4), 0, 0}};
	mvod_view_add_pose(&v, &down, 0);
	assert_true(isnan(mvod_view_yaw_deg(&v)));
	mvod_view_fini(&v);
}

static void test_rate_and_staleness(void **state)
{
	(void)state;
	struct mvod_view v;
	struct mvod_view_row rows[MVOD_VIEW_MAX_ROWS];
	assert_int_equal(mvod_view_init(&v, 100), 0);
	/* 20 Hz for 3 s on the receive clock. */
	int64_t t = 0;
	for (int i = 0; i < 61; i++, t += 50000) {
		mvod_pose_t p = pose_at(i, 0);
		mvod_view_add_pose(&v, &p, t);
	}
	assert_true(fabs(v.pose_hz - 20.0) < 1e-9);
	int n = mvod_view_rows(&v, t, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "poses received"), "20.0 /s");
	/* Nothing for 5 s: the rate is not shown as if mvod were still running. */
	n = mvod_view_rows(&v, t + 5000000, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "poses received"), "none for 5 s");
	mvod_view_fini(&v);
}

static void test_memory_fixed(void **state)
{
	(void)state;
	struct mvod_view v;
	assert_int_equal(mvod_view_init(&v, 100), 0);
	double *buf = v.path.xyz;
	for (int i = 0; i < 100000; i++) {
		mvod_pose_t p = pose_at(i, 0);
		mvod_view_add_pose(&v, &p, i);
	}
	assert_ptr_equal(v.path.xyz, buf);
	assert_true(v.path.n <= 100 && v.path.n >= 50);
	assert_int_equal(v.poses, 100000);
	/* The latest pose is kept whole, whatever the path dropped. */
	assert_true(v.pose.t[2] == 99999.0);
	mvod_view_fini(&v);
}

static void test_newest_state_and_rows(void **state)
{
	(void)state;
	struct mvod_view v;
	struct mvod_view_row rows[MVOD_VIEW_MAX_ROWS];
	assert_int_equal(mvod_view_init(&v, 100), 0);
	int n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "poses"), "none yet");
	mvod_pose_t p = pose_at(1, 0);
	mvod_view_add_pose(&v, &p, 0);
	assert_int_equal(v.state, MVOD_STATE_TRACKING);
	/* Status comes on its own while the source is away, with no pose: it wins. */
	mvod_status_t st = {.state = MVOD_POSE_T_STATE_SOURCE_DOWN, .fps = 29.75f,
			    .dropped_frames = 7, .rss_kb = 51200, .uptime_s = 3725.4};
	mvod_view_add_status(&v, &st);
	assert_int_equal(v.state, MVOD_RUN_SOURCE_DOWN);
	n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "mvod fps"), "29.8");
	assert_string_equal(value_of(rows, n, "dropped frames"), "7");
	assert_string_equal(value_of(rows, n, "RSS"), "50.0 MiB");
	assert_string_equal(value_of(rows, n, "uptime"), "1:02:05");
	assert_string_equal(value_of(rows, n, "messages"), "1 poses, 1 status");
	/* A short array gets the first rows, not an overflow. */
	assert_int_equal(mvod_view_rows(&v, 0, rows, 2), 2);
	mvod_view_fini(&v);
}

/*
 * After mvod's last status (STOPPING) the view keeps the state the run stopped in, and whether
 * it ever tracked (issue 18: the end-of-log picture always said STOPPING).
 */
static void test_state_before_stopping(void **state)
{
	(void)state;
	struct mvod_view v;
	struct mvod_view_row rows[MVOD_VIEW_MAX_ROWS];
	assert_int_equal(mvod_view_init(&v, 100), 0);
	mvod_pose_t p = pose_at(0, 0);
	p.state = MVOD_POSE_T_STATE_INITIALIZING;
	for (int i = 0; i < 3; i++)
		mvod_view_add_pose(&v, &p, i);
	mvod_status_t st = {.state = MVOD_POSE_T_STATE_STOPPING};
	mvod_view_add_status(&v, &st);
	assert_int_equal(v.state, MVOD_RUN_STOPPING);
	assert_int_equal(v.last_state, MVOD_RUN_INITIALIZING);
	assert_int_equal(v.tracked, 0);
	int n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "tracked"), "never");
	p.state = MVOD_POSE_T_STATE_TRACKING;
	mvod_view_add_pose(&v, &p, 4);
	p.state = MVOD_POSE_T_STATE_LOST;
	mvod_view_add_pose(&v, &p, 5);
	mvod_view_add_status(&v, &st);
	assert_int_equal(v.last_state, MVOD_RUN_LOST);
	n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "tracked"), "1 of 5 poses");
	mvod_view_fini(&v);
}

/* The faults mvod reports show by name, and only when there are some. */
static void test_faults_row(void **state)
{
	(void)state;
	struct mvod_view v;
	struct mvod_view_row rows[MVOD_VIEW_MAX_ROWS];
	assert_int_equal(mvod_view_init(&v, 100), 0);
	mvod_status_t st = {.state = MVOD_POSE_T_STATE_TRACKING};
	mvod_view_add_status(&v, &st);
	int n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	for (int i = 0; i < n; i++)
		assert_string_not_equal(rows[i].label, "faults");
	st.faults = MVOD_STATUS_T_FAULT_TRAJECTORY_WRITE | MVOD_STATUS_T_FAULT_PUBLISH;
	mvod_view_add_status(&v, &st);
	n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "faults"), "trajectory, publish");
	st.faults = 15; /* all four: the longest value still fits a row */
	mvod_view_add_status(&v, &st);
	n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "faults"),
			    "trajectory, bad frames, source broken, publish");
	mvod_view_fini(&v);
}

static void test_plot_draw_checks_image(void **state)
{
	(void)state;
	static uint8_t px[MVOD_PLOT_HEIGHT][MVOD_PLOT_WIDTH][3];
	const double xyz[] = {0, 0, 0, 1, 0, 2};
	struct mvod_image img = {MVOD_PLOT_WIDTH, MVOD_PLOT_HEIGHT, MVOD_PLOT_WIDTH * 3,
				 MVOD_PIX_BGR, &px[0][0][0]};
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 2, NULL, NULL, 0, "m"), 0);
	/* The plot's white background is there, written through the caller's view. */
	assert_int_equal(px[0][0][0], 255);
	img.w = 640;
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 2, NULL, NULL, 0, "m"), -EINVAL);
	img.w = MVOD_PLOT_WIDTH;
	img.fmt = MVOD_PIX_GREY;
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 2, NULL, NULL, 0, "m"), -EINVAL);
}

/*
 * Positions are labelled metres only when the steps' length came from ground truth; structure,
 * constant speed and a free-scale run's first (unit) step give units of that first step.
 */
static void test_unit_follows_scale_source(void **state)
{
	(void)state;
	struct mvod_view v;
	struct mvod_view_row rows[MVOD_VIEW_MAX_ROWS];
	assert_int_equal(mvod_view_init(&v, 100), 0);
	/* Before any pose nothing says metres. */
	assert_string_equal(mvod_view_unit(&v, false), "units, free scale");
	static const struct {
		int8_t source;
		const char *unit, *row;
	} steps[] = {
		{MVOD_POSE_T_SCALE_UNIT, "units, free scale", "position [units]"},
		{MVOD_POSE_T_SCALE_STRUCTURE, "units, free scale", "position [units]"},
		{MVOD_POSE_T_SCALE_CONSTANT_SPEED, "units, free scale", "position [units]"},
		{MVOD_POSE_T_SCALE_GROUND_TRUTH, "m", "position [m]"},
		/* A held frame has no step: the run is still metric. */
		{MVOD_POSE_T_SCALE_NONE, "m", "position [m]"},
		{MVOD_POSE_T_SCALE_STRUCTURE, "units, free scale", "position [units]"},
		{MVOD_POSE_T_SCALE_NONE, "units, free scale", "position [units]"},
		{MVOD_POSE_T_SCALE_HEIGHT, "m", "position [m]"},
		{MVOD_POSE_T_SCALE_MAP, "units, free scale", "position [units]"},
		{MVOD_POSE_T_SCALE_EXTERNAL, "m", "position [m]"},
	};
	for (size_t i = 0; i < sizeof(steps) / sizeof(steps[0]); i++) {
		mvod_pose_t p = pose_at((double)i, 0);
		p.scale_source = steps[i].source;
		mvod_view_add_pose(&v, &p, 0);
		assert_string_equal(mvod_view_unit(&v, false), steps[i].unit);
		int n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
		char where[32];
		snprintf(where, sizeof(where), "0.00 0.00 %zu.00", i);
		assert_string_equal(value_of(rows, n, steps[i].row), where);
	}
	mvod_view_fini(&v);
}

/* The unit reaches the axes: the same path with another unit is another picture. */
static void test_plot_draw_unit(void **state)
{
	(void)state;
	static uint8_t a[MVOD_PLOT_HEIGHT][MVOD_PLOT_WIDTH][3], b[MVOD_PLOT_HEIGHT][MVOD_PLOT_WIDTH][3];
	const double xyz[] = {0, 0, 0, 1, 0, 2};
	struct mvod_image img = {MVOD_PLOT_WIDTH, MVOD_PLOT_HEIGHT, MVOD_PLOT_WIDTH * 3,
				 MVOD_PIX_BGR, &a[0][0][0]};
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 2, NULL, NULL, 0, "m"), 0);
	img.data = &b[0][0][0];
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 2, NULL, NULL, 0,
						"units, free scale"), 0);
	assert_true(memcmp(a, b, sizeof(a)) != 0);
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 2, NULL, NULL, 0, NULL), -EINVAL);
}

/*
 * The plot is drawn straight into the caller's pixels: every one of them is painted, whatever
 * was there before (a redraw leaves nothing of the last picture), and nothing past the row's
 * width (a wider stride's padding) is touched.
 */
static void test_plot_draw_paints_every_pixel(void **state)
{
	(void)state;
	enum { ROW = MVOD_PLOT_WIDTH * 3, STRIDE = ROW + 64, SIZE = STRIDE * MVOD_PLOT_HEIGHT };
	static uint8_t a[SIZE], b[SIZE];
	memset(a, 0x00, sizeof(a));
	memset(b, 0x5a, sizeof(b));
	const double xyz[] = {0, 0, 0, 1, 0, 2, 3, 0, 2.5};
	struct mvod_image img = {MVOD_PLOT_WIDTH, MVOD_PLOT_HEIGHT, STRIDE, MVOD_PIX_BGR, a};
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 3, NULL, NULL, 0, "m"), 0);
	img.data = b;
	assert_int_equal(mvod_plot_topdown_draw(&img, "t", xyz, 3, NULL, NULL, 0, "m"), 0);
	for (int y = 0; y < MVOD_PLOT_HEIGHT; y++) {
		assert_memory_equal(a + y * STRIDE, b + y * STRIDE, ROW);
		for (int k = ROW; k < STRIDE; k++)
			assert_int_equal(b[y * STRIDE + k], 0x5a);
	}
}

/*
 * A log of an mvod that published only v1 is shown (without the v2 rows); once a v2 message
 * came, the v1 twins mvod publishes beside them count no more, and the panel shows quality,
 * map points and keyframes, scale and latency.
 */
static void test_v2_and_v1(void **state)
{
	(void)state;
	struct mvod_view v;
	struct mvod_view_row rows[MVOD_VIEW_MAX_ROWS];
	assert_int_equal(mvod_view_init(&v, 100), 0);
	mvod_pose_t p1 = pose_at(1, 0);
	mvod_status_t s1 = {.state = MVOD_POSE_T_STATE_TRACKING, .frames = 1};
	mvod_view_add_pose(&v, &p1, 0);
	mvod_view_add_status(&v, &s1);
	assert_int_equal(v.poses, 1);
	assert_int_equal(v.statuses, 1);
	int n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	for (int i = 0; i < n; i++)
		assert_true(strcmp(rows[i].label, "quality") && strcmp(rows[i].label, "latency"));

	mvod_pose2_t p2 = {.position = {0, 0, 2}, .orientation = {1, 0, 0, 0},
			   .state = MVOD_POSE_T_STATE_TRACKING, .quality = 0.75f, .keyframe = 1};
	mvod_status2_t s2 = {.state = MVOD_POSE_T_STATE_TRACKING, .frames = 2, .map_points = 900,
			     .keyframes = 12, .scale = 0.5, .scale_confidence = 0.25f,
			     .latency_ms = 7.5f};
	mvod_view_add_pose2(&v, &p2, 0);
	mvod_view_add_status2(&v, &s2);
	mvod_pose_t late = pose_at(5, 0);
	mvod_view_add_pose(&v, &late, 0);
	mvod_view_add_status(&v, &s1);
	assert_int_equal(v.poses, 2);
	assert_int_equal(v.statuses, 2);
	assert_true(v.pose.t[2] == 2);
	n = mvod_view_rows(&v, 0, rows, MVOD_VIEW_MAX_ROWS);
	assert_string_equal(value_of(rows, n, "quality"), "0.75");
	assert_string_equal(value_of(rows, n, "map points/keyfr."), "900 / 12");
	assert_string_equal(value_of(rows, n, "scale"), "0.5 m/unit (conf. 0.25)");
	assert_string_equal(value_of(rows, n, "latency"), "7.5 ms");
	assert_string_equal(value_of(rows, n, "frames"), "2");
	mvod_view_fini(&v);
}

/*
 * A log's state byte that is no state shows as UNKNOWN: loaded into the enum as it was, the
 * drawing (C++) read an out-of-range value (UBSan: "load of value 100"); the PNG is drawn.
 */
static void test_unknown_state(void **state)
{
	(void)state;
	struct mvod_view v;
	assert_int_equal(mvod_view_init(&v, 100), 0);
	mvod_status_t st = {.state = 100};
	mvod_view_add_status(&v, &st);
	assert_int_equal(v.state, MVOD_RUN_UNKNOWN);
	assert_int_equal(v.status.state, MVOD_RUN_UNKNOWN);
	assert_int_equal(v.last_state, MVOD_RUN_UNKNOWN);
	mvod_pose_t p = pose_at(1, 0);
	p.state = -7;
	mvod_view_add_pose(&v, &p, 0);
	assert_int_equal(v.state, MVOD_RUN_UNKNOWN);
	assert_string_equal(mvod_run_state_name(v.state), "UNKNOWN");
	char png[64];
	snprintf(png, sizeof(png), "/tmp/mvod-test-view-%d.png", (int)getpid());
	struct mvod_view_labels l = {"unknown", NULL};
	assert_int_equal(mvod_view_write_png(&v, 0, &l, png), 0);
	unlink(png);
	mvod_view_fini(&v);
}

/* A pose message that is no pose is not drawn (the path and heading went nan), only counted. */
static void test_refused_pose(void **state)
{
	(void)state;
	struct mvod_view v;
	assert_int_equal(mvod_view_init(&v, 100), 0);
	mvod_pose_t p = pose_at(1, 0);
	mvod_view_add_pose(&v, &p, 0);
	p.orientation[0] = 0; /* a zero quaternion */
	p.frame = 7;
	mvod_view_add_pose(&v, &p, 1);
	p = pose_at(NAN, 0);
	mvod_view_add_pose(&v, &p, 2);
	assert_int_equal(v.poses, 1);
	assert_int_equal(v.refused, 2);
	assert_non_null(strstr(v.refused_why, "frame 7: quaternion (qx qy qz qw) = (0 0 0 0)"));
	assert_true(v.pose.t[2] == 1 && isfinite(mvod_view_yaw_deg(&v)));
	assert_int_equal(v.path.n, 1);
	mvod_view_fini(&v);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_v2_and_v1),
		cmocka_unit_test(test_yaw),
		cmocka_unit_test(test_rate_and_staleness),
		cmocka_unit_test(test_memory_fixed),
		cmocka_unit_test(test_newest_state_and_rows),
		cmocka_unit_test(test_state_before_stopping),
		cmocka_unit_test(test_faults_row),
		cmocka_unit_test(test_plot_draw_checks_image),
		cmocka_unit_test(test_plot_draw_paints_every_pixel),
		cmocka_unit_test(test_unit_follows_scale_source),
		cmocka_unit_test(test_plot_draw_unit),
		cmocka_unit_test(test_unknown_state),
		cmocka_unit_test(test_refused_pose),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
