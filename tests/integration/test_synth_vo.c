/*
 * The real binary on mvod-synth sequences, against their exact ground truth: the default
 * (map mode, KLT tracks), and two-view mode (--mode twoview) where a case says so.
 *
 * Bounds: the renderer is exact (sub-pixel flow agrees with the geometry to 0.02 px), so the
 * error comes from ORB's localisation (median 0.32 px on these frames) and from the short
 * baseline: 0.1 m per frame at 3-30 m depth is 0.2-3 px of parallax, so a 0.3 px error tilts
 * the translation direction by several degrees while the rotation stays within ~0.1 deg.
 * Each bound is about twice the value measured when it was set (in the comments: two-view on
 * ORB then), so a wrong decomposition, a sign error, a lost frame or a scale blow-up fails it.
 * The KLT tracks of today's default measure several times less (the "now" figures: map mode,
 * the default since issue 12, then two-view); test_klt.c bounds KLT itself more tightly.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

struct vo_case {
	const char *path;
	int frames;
	const char *scale;    /* "gt" or "auto" */
	const char *label;    /* names the output folder when extra or mode is set */
	const char *extra[5]; /* more mvod-synth arguments (lens), NULL-terminated */
	const char *mode;     /* --mode; NULL: the default, map mode */
};

static void run_vo(const struct vo_case *c, struct traj_errors *e)
{
	char dir[256], video[300], calib[300], gt[300], out[300];
	snprintf(dir, sizeof(dir), "%s/%s-%s%s", harness_tmpdir(), c->path, c->scale,
		 c->label ? c->label : "");
	harness_synth(dir, c->path, c->frames, "mkv", c->extra[0], c->extra[1], c->extra[2],
		      c->extra[3], c->extra[4], NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(gt, sizeof(gt), "%s/gt.tum", dir);
	snprintf(out, sizeof(out), "%s/est.tum", dir);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib, "--gt", gt,
			"--scale", (char *)c->scale, "--trajectory", out, "--no-lcm", NULL, NULL, NULL};
	if (c->mode) {
		argv[12] = "--mode";
		argv[13] = (char *)c->mode;
	}
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod failed (%d): %s", r.status, r.err);
	harness_compare(out, gt, strcmp(c->scale, "auto") == 0, e);
	print_message("%s/%s %s: %d frames, rot %.4f deg/frame (max %.4f), dir %.3f deg (max %.3f), "
		      "ATE %.4f m over %.2f m, scale %.4f, max |t| %.4f\n",
		      c->path, c->scale, c->mode ? c->mode : "default", e->n, e->rpe.rot_deg_mean,
		      e->rpe.rot_deg_max, e->rpe.dir_deg_mean, e->rpe.dir_deg_max, e->ate_m,
		      e->length_m, e->scale, e->max_translation);
	assert_int_equal(e->n, c->frames);
}

static void test_forward_gt_scale(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){.path = "forward", .frames = 60, .scale = "gt"}, &e);
	/* Now 0.0046 / 0.0116 deg, 0.33 deg, 0.0021 m (two-view: 0.0040, 0.0111, 0.25, 0.0016). */
	assert_true(e.rpe.rot_deg_mean < 0.16); /* measured 0.082 */
	assert_true(e.rpe.rot_deg_max < 0.4);   /* 0.185 */
	assert_true(e.rpe.dir_deg_mean < 10);   /* 5.6 */
	assert_true(e.ate_m < 0.015 * e.length_m); /* 0.031 m over 5.9 m */
}

static void test_turn_gt_scale(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){.path = "turn", .frames = 80, .scale = "gt"}, &e);
	/* Now 0.0060 / 0.0143 deg, 0.40 deg, 0.0024 m (two-view: 0.0079, 0.0251, 0.53, 0.0029). */
	assert_true(e.rpe.rot_deg_mean < 0.12); /* measured 0.053 */
	assert_true(e.rpe.rot_deg_max < 0.4);   /* 0.163 */
	assert_true(e.rpe.dir_deg_mean < 7);    /* 3.5 */
	assert_true(e.ate_m < 0.015 * e.length_m); /* 0.028 m over 7.9 m */
}

static void test_forward_free_scale(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){.path = "forward", .frames = 60, .scale = "auto"}, &e);
	assert_true(e.rpe.rot_deg_mean < 0.16); /* now 0.0188 (two-view: 0.0040) */
	/*
	 * After Sim(3) alignment the path lies within 2 % of its length of the truth. Measured
	 * 0.053 m over 5.9 m; now 0.0228 m (two-view: 0.0084): map mode holds the position
	 * through its first frames, until a step has parallax enough for a map.
	 */
	assert_true(e.ate_m < 0.02 * e.length_m);
}

/*
 * Two-view mode (--mode twoview), kept for comparison, on the same path: its bounds and
 * measured values are the ones the tests above had while two-view was the default.
 */
static void test_forward_gt_scale_twoview(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){"forward", 60, "gt", "-twoview", {NULL}, "twoview"}, &e);
	assert_true(e.rpe.rot_deg_mean < 0.16); /* measured 0.082 (ORB); now 0.0040 */
	assert_true(e.rpe.rot_deg_max < 0.4);   /* 0.185; 0.0111 */
	assert_true(e.rpe.dir_deg_mean < 10);   /* 5.6; 0.25 */
	assert_true(e.ate_m < 0.015 * e.length_m); /* 0.031 m over 5.9 m; 0.0016 m */
}

static void test_forward_free_scale_twoview(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){"forward", 60, "auto", "-twoview", {NULL}, "twoview"}, &e);
	assert_true(e.rpe.rot_deg_mean < 0.16);
	assert_true(e.ate_m < 0.02 * e.length_m); /* measured 0.053 m over 5.9 m (ORB); 0.0084 m */
}

static void test_turn_free_scale(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){.path = "turn", .frames = 80, .scale = "auto"}, &e);
	assert_true(e.rpe.rot_deg_mean < 0.12); /* now 0.0170 (two-view: 0.0079) */
	/* Measured 0.071 m over 7.9 m; now 0.0272 m (two-view: 0.0283 m). */
	assert_true(e.ate_m < 0.02 * e.length_m);
}

/* Undistortion through the remap maps: a strongly barrel-distorted pinhole lens. */
static void test_turn_radtan_lens(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){"turn", 80, "gt", "-radtan",
				 {"--distortion", "-0.3,0.1,0.001,-0.001,0", NULL}, NULL},
	       &e);
	assert_true(e.rpe.rot_deg_mean < 0.12); /* measured 0.047 */
	assert_true(e.rpe.rot_deg_max < 0.3);   /* 0.114 */
	assert_true(e.rpe.dir_deg_mean < 6);    /* 2.9 */
	assert_true(e.ate_m < 0.015 * e.length_m); /* 0.016 m over 7.9 m */
}

/*
 * A wide Kannala-Brandt lens (f = 300 px, about 94 deg across): half the focal length, so
 * about twice the angular error of the pinhole cases.
 */
static void test_turn_fisheye_lens(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){"turn", 80, "gt", "-fisheye",
				 {"--fisheye", "0.05,-0.01,0.002,0", "--fx", "300", NULL}, NULL},
	       &e);
	assert_true(e.rpe.rot_deg_mean < 0.3); /* measured 0.164 */
	assert_true(e.rpe.rot_deg_max < 0.7);  /* 0.350 */
	assert_true(e.rpe.dir_deg_mean < 12);  /* 6.6 */
	assert_true(e.ate_m < 0.02 * e.length_m); /* 0.060 m over 7.9 m */
}

/*
 * Free scale on a path whose speed keeps changing: from 0.5 to 1.5 m/s, braking to a stop,
 * standing, pulling away (mvod-synth's stop-go). Measured: ATE 1.29 % of the path, scale drift
 * 1.31 (largest over smallest scale of 20-step windows; the last 10 % of the path against the
 * first: 0.614). That is no better than carrying the last step forward (constant speed alone:
 * 1.53 %, last against first 0.682): at 0.1 m steps fewer
 * than 10 point pairs lie within the 50 baselines structure scale needs in most frames, and
 * where it does work it drifts (issue: free-scale drift on variable speed). Until the VO does
 * better, the bounds catch a scale that collapses or blows up: windows' scales within a factor
 * of 2 of each other, ATE twice the measured. Now (KLT): map mode 0.27 %, drift 1.008;
 * two-view 0.11 %, 1.043.
 */
static void test_stop_go_free_scale(void **state)
{
	(void)state;
	struct traj_errors e;
	run_vo(&(struct vo_case){.path = "stop-go", .frames = 100, .scale = "auto"}, &e);
	print_message("stop-go: scale drift %.4f\n", e.scale_drift);
	assert_true(e.rpe.rot_deg_mean < 0.16); /* measured 0.061 */
	assert_true(e.ate_m < 0.026 * e.length_m);
	assert_true(e.scale_drift < 2.0);
}

/* Identical frames carry no parallax: not a millimetre (or unit) of invented motion. */
static void static_no_drift(const struct vo_case *c)
{
	struct traj_errors e;
	run_vo(c, &e);
	assert_true(e.max_translation < 1e-6);
	assert_true(e.rpe.rot_deg_max < 0.01);
}

static void test_static_no_drift(void **state)
{
	(void)state;
	static_no_drift(&(struct vo_case){.path = "static", .frames = 40, .scale = "auto"});
}

/* Two-view mode: a camera that does not translate, as above. */
static void test_static_no_drift_twoview(void **state)
{
	(void)state;
	static_no_drift(&(struct vo_case){"static", 40, "auto", "-twoview", {NULL}, "twoview"});
}

/*
 * Pure rotation has no baseline: any translation would be invented. Measured (ORB, two-view):
 * rotation 0.016 deg/frame (max 0.067); KLT: map 0.0015 (0.0064), two-view 0.0020 (0.0102).
 */
static void rotate_in_place_no_drift(const struct vo_case *c)
{
	struct traj_errors e;
	run_vo(c, &e);
	assert_true(e.rpe.rot_deg_mean < 0.04);
	assert_true(e.rpe.rot_deg_max < 0.15);
	assert_true(e.max_translation < 1e-6);
}

static void test_rotate_in_place_no_drift(void **state)
{
	(void)state;
	rotate_in_place_no_drift(
		&(struct vo_case){.path = "rotate-in-place", .frames = 60, .scale = "auto"});
}

static void test_rotate_in_place_no_drift_twoview(void **state)
{
	(void)state;
	rotate_in_place_no_drift(
		&(struct vo_case){"rotate-in-place", 60, "auto", "-twoview", {NULL}, "twoview"});
}

static void test_black_frames_hold_and_recover(void **state)
{
	(void)state;
	char dir[256], src[400], images[300], calib[300], gt[300], out[300];
	snprintf(dir, sizeof(dir), "%s/black", harness_tmpdir());
	harness_synth(dir, "forward", 30, "png", NULL);
	snprintf(images, sizeof(images), "%s/images", dir);
	harness_blacken(images, 10, 640, 480);
	harness_blacken(images, 11, 640, 480);
	snprintf(src, sizeof(src), "images:%s", images);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(gt, sizeof(gt), "%s/gt.tum", dir);
	snprintf(out, sizeof(out), "%s/est.tum", dir);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", src, "--calib", calib, "--gt", gt,
			"--scale", "gt", "--trajectory", out, "--no-lcm", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod failed (%d): %s", r.status, r.err);
	assert_non_null(strstr(r.err, "LOST"));
	struct mvod_traj est;
	char err[256];
	assert_int_equal(mvod_traj_load(out, &est, err, sizeof(err)), 0);
	assert_int_equal(est.n, 30);
	/* The black frames hold the last pose exactly... */
	assert_memory_equal(&est.pose[10], &est.pose[9], sizeof(est.pose[9]));
	assert_memory_equal(&est.pose[11], &est.pose[9], sizeof(est.pose[9]));
	mvod_traj_free(&est);
	/* ...and tracking resumes against the last good frame: the path stays right. */
	struct traj_errors e;
	harness_compare(out, gt, 0, &e);
	assert_true(e.ate_m < 0.05 * e.length_m);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_forward_gt_scale),
		cmocka_unit_test(test_turn_gt_scale),
		cmocka_unit_test(test_forward_free_scale),
		cmocka_unit_test(test_forward_gt_scale_twoview),
		cmocka_unit_test(test_forward_free_scale_twoview),
		cmocka_unit_test(test_turn_free_scale),
		cmocka_unit_test(test_turn_radtan_lens),
		cmocka_unit_test(test_turn_fisheye_lens),
		cmocka_unit_test(test_stop_go_free_scale),
		cmocka_unit_test(test_static_no_drift),
		cmocka_unit_test(test_rotate_in_place_no_drift),
		cmocka_unit_test(test_static_no_drift_twoview),
		cmocka_unit_test(test_rotate_in_place_no_drift_twoview),
		cmocka_unit_test(test_black_frames_hold_and_recover),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
