/*
 * mvod mount's parts: the mount from a board pose (the inverse of scale.c's ground normal, so
 * what mvod mount writes is what --scale height reads), its uncertainty, the average that
 * drops views off the floor, and the camera file rewritten with every other field kept.
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/calib.h"
#include "mvod/geom.h"
#include "mvod/mount.h"
#include "vo/core/camera.h"

/* Closed-form round trips in doubles: rounding is ~1e-15; 1e-9 is still far below any bug. */
#define EXACT 1e-9

/* The pose of a board lying on the floor of a camera mounted at (h, pitch, roll), turned by yaw. */
static void floor_pose(double h, double pitch, double roll, double yaw, double rvec[3], double t[3])
{
	double n[3];
	mvod_ground_normal(pitch, roll, n);
	/* f: the camera's forward along the floor; g = n x f its right; board x, y = n x x. */
	double f[3] = {-n[2] * n[0], -n[2] * n[1], 1 - n[2] * n[2]}, g[3], x[3], y[3];
	double fl = mvod_vec3_norm(f);
	for (int i = 0; i < 3; i++)
		f[i] /= fl;
	g[0] = n[1] * f[2] - n[2] * f[1];
	g[1] = n[2] * f[0] - n[0] * f[2];
	g[2] = n[0] * f[1] - n[1] * f[0];
	for (int i = 0; i < 3; i++)
		x[i] = cos(yaw) * g[i] + sin(yaw) * f[i];
	y[0] = n[1] * x[2] - n[2] * x[1];
	y[1] = n[2] * x[0] - n[0] * x[2];
	y[2] = n[0] * x[1] - n[1] * x[0];
	const double R[9] = {x[0], y[0], n[0], x[1], y[1], n[1], x[2], y[2], n[2]};
	mvod_rot_log(R, rvec);
	/* Board origin 2 m ahead and 0.3 m to the right on the floor. */
	for (int i = 0; i < 3; i++)
		t[i] = h * n[i] + 2 * f[i] + 0.3 * g[i];
}

static void test_from_pose_inverts_ground_normal(void **state)
{
	(void)state;
	const double cases[][4] = {{1.6, 0, 0, 0}, {1.65, 5, -2, 0.3}, {0.5, 25, -3, -0.5},
				   {0.3, 59, 40, 1}, {3, -10, 15, 0.1}};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		double r[3], t[3];
		floor_pose(cases[i][0], cases[i][1], cases[i][2], cases[i][3], r, t);
		struct mvod_mount m;
		mvod_mount_from_pose(r, t, 0, &m);
		assert_true(fabs(m.height_m - cases[i][0]) < EXACT);
		assert_true(fabs(m.pitch_deg - cases[i][1]) < EXACT);
		assert_true(fabs(m.roll_deg - cases[i][2]) < EXACT);
		/* The board's thickness lifts its face: the floor is that much further. */
		mvod_mount_from_pose(r, t, 0.004, &m);
		assert_true(fabs(m.height_m - cases[i][0] - 0.004) < EXACT);
	}
}

/* The uncertainty of a level camera's mount: the height is t_y, the pitch a turn about x. */
static void test_sd(void **state)
{
	(void)state;
	double r[3], t[3], cov[36] = {0};
	floor_pose(1.6, 0, 0, 0, r, t);
	cov[6 * 4 + 4] = 1e-6;              /* var t_y: 1 mm */
	cov[0] = pow(0.5 * M_PI / 180, 2); /* var rx: 0.5 deg */
	struct mvod_mount sd;
	mvod_mount_sd(r, t, cov, &sd);
	/*
	 * rvec perturbs R on the left; at R = identity-like axes a 0.5 deg turn about x is 0.5 deg
	 * of pitch and moves n . t by 2 m * sin(0.5 deg) = 17.5 mm; central differences of 1e-6
	 * are exact to ~1e-6 relative here.
	 */
	assert_true(fabs(sd.pitch_deg - 0.5) < 1e-3);
	assert_true(fabs(sd.roll_deg) < 1e-3);
	assert_true(sd.height_m > 0.001 && sd.height_m < 0.02);
}

static void test_combine_drops_a_lifted_board(void **state)
{
	(void)state;
	struct mvod_mount_view v[6];
	for (int i = 0; i < 6; i++)
		v[i] = (struct mvod_mount_view){.frame = i, .m = {1.6 + 0.001 * (i % 2), 20, -1},
						.sd = {0.002, 0.05, 0.05}, .verdict = MVOD_MOUNT_USED};
	v[0].sd.height_m = 0.001; /* twice as sure: four times the weight */
	v[3].m.height_m = 1.5;    /* the board on a box, 10 cm up: 50 sigma off */
	v[5].verdict = MVOD_MOUNT_UNCERTAIN;
	v[5].m.height_m = 9;      /* refused before: takes no part, not even in the median */
	struct mvod_mount m, sd;
	assert_int_equal(mvod_mount_combine(v, 6, &m, &sd), 4);
	assert_int_equal(v[3].verdict, MVOD_MOUNT_DISAGREES);
	assert_int_equal(v[5].verdict, MVOD_MOUNT_UNCERTAIN);
	/* Weights 4, 1, 1, 1 on 1.600, 1.601, 1.600, 1.600 (views 0, 1, 2, 4). */
	assert_true(fabs(m.height_m - (4 * 1.6 + 1.601 + 1.6 + 1.6) / 7) < EXACT);
	assert_true(fabs(sd.height_m - 1 / sqrt(7 / 4e-6)) < EXACT);
	assert_true(fabs(m.pitch_deg - 20) < EXACT && fabs(m.roll_deg + 1) < EXACT);
}

/* Rewritten with every field of mvod calibrate's file kept, the mount added, then replaced. */
/* The FOV lens is refused before any frame is read: OpenCV undistorts the board's corners. */
static void test_measure_refuses_fov(void **state)
{
	(void)state;
	struct mvod_mount_opts o = {.source = "images:/nonexistent"};
	struct mvod_camera cam = {.width = 640, .height = 480, .fx = 400, .fy = 400, .cx = 320,
				  .cy = 240, .model = MVOD_CAM_FOV, .n_dist = 1, .dist = {0.9}};
	struct mvod_mount_result res;
	char err[512] = "";
	assert_int_equal(mvod_mount_measure(&o, &cam, &res, err, sizeof(err)), -ENOTSUP);
	assert_non_null(strstr(err, "the camera file's lens is FOV"));
	mvod_mount_result_free(&res);
}

static void test_write_keeps_fields(void **state)
{
	(void)state;
	const char *path = harness_tmp_path("cam.json");
	struct mvod_camera cam = {.width = 640, .height = 480, .fx = 500, .fy = 501, .cx = 320.25,
				  .cy = 240.125, .n_dist = 5, .dist = {-0.1, 0.01, 1e-4, -2e-4, 0.001}};
	const double rms[2] = {0.2, 0.3}, pose[12] = {0.1, 0.2, 0.3, 1, 2, 3, 0.4, 0.5, 0.6, 4, 5, 6};
	struct mvod_calib_meta meta = {.rms_px = 0.25, .board = "charuco:5x7:0.04:0.02:DICT_6X6_250",
				       .source = "file:x.mkv", .n_views = 2, .view_rms_px = rms,
				       .view_pose = pose, .verdict = "good"};
	assert_int_equal(mvod_calib_save(path, &cam, &meta), 0);
	static char before[8192], after[8192], again[8192];
	harness_read_file(path, before, sizeof(before));
	char err[512];
	const struct mvod_mount m = {1.234567, 12.3456, -1.2345};
	assert_int_equal(mvod_mount_write(path, before, &m, err, sizeof(err)), 0);
	harness_read_file(path, after, sizeof(after));
	/* Everything before the closing brace is as it was; the mount follows, rounded. */
	size_t keep = strlen(before) - strlen("\n}\n");
	assert_memory_equal(after, before, keep);
	assert_string_equal(after + keep, ",\n\t\"mount\":\t{\n\t\t\"height_m\":\t1.2346,\n"
					  "\t\t\"pitch_deg\":\t12.35,\n\t\t\"roll_deg\":\t-1.23\n\t}\n}\n");
	/* A second measurement replaces the block in its place: the text is as long, and new. */
	const struct mvod_mount m2 = {1.5, -2, 3};
	assert_int_equal(mvod_mount_write(path, after, &m2, err, sizeof(err)), 0);
	harness_read_file(path, again, sizeof(again));
	assert_memory_equal(again, before, keep);
	assert_non_null(strstr(again + keep, "\"height_m\":\t1.5,"));
	assert_null(strstr(strstr(again, "\"mount\"") + 1, "\"mount\""));
	/* The parser reads it back (last: loading notes the file as an input, not to be written). */
	struct mvod_camera back;
	assert_int_equal(mvod_calib_load(path, &back, err, sizeof(err)), 0);
	assert_true(back.has_mount && back.mount_height_m == 1.5 && back.mount_pitch_deg == -2 &&
		    back.mount_roll_deg == 3);
	assert_true(back.fx == cam.fx && back.cy == cam.cy && back.dist[4] == cam.dist[4]);
}

/* A file mvod did not write (or that is not mvod JSON) is refused, and left as it was. */
static void test_write_refuses_other_files(void **state)
{
	(void)state;
	const char *path = harness_tmp_path("pair.json");
	const char *text = "[[[500, 0, 320], [0, 500, 240], [0, 0, 1]], [0, 0, 0, 0]]\n";
	harness_write_file(path, text);
	char err[512], now[512];
	const struct mvod_mount m = {1.6, 0, 0};
	assert_int_equal(mvod_mount_write(path, text, &m, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "not mvod JSON"));
	assert_non_null(strstr(err, "mvod calib-convert"));
	harness_read_file(path, now, sizeof(now));
	assert_string_equal(now, text);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_from_pose_inverts_ground_normal),
		cmocka_unit_test(test_sd),
		cmocka_unit_test(test_combine_drops_a_lifted_board),
		cmocka_unit_test(test_measure_refuses_fov),
		cmocka_unit_test(test_write_keeps_fields),
		cmocka_unit_test(test_write_refuses_other_files),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
