/*
 * The real KITTI 06 and 07 clips in ../shared/data, ground-truth scale. Skips (77) when the
 * data is absent. The bounds are regression bounds: the values measured when they were set
 * (in the comments) plus a margin for platform differences in OpenCV's RANSAC.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/capture.h"

struct clip {
	const char *seq;
	const char *frontend; /* --frontend */
	const char *mode;     /* --mode */
	int frames;
	double rot_mean, rot_max, dir_mean; /* bounds, degrees */
	double ate_m;         /* with --scale height: bound on the ATE (SE(3), metres) */
	int tracks;           /* --tracks, 0: the default */
};

/* Runs mvod on the clip and checks the bounds; returns the SE(3) ATE, metres. */
static double run_clip(const struct clip *c)
{
	const char *data = getenv("MVOD_DATA");
	char seqdir[512], src[600], gt[600], out[600];
	snprintf(seqdir, sizeof(seqdir), "%s/kitti-odometry-%s-clip/sequences/%s", data, c->seq, c->seq);
	snprintf(src, sizeof(src), "kitti:%s", seqdir);
	snprintf(gt, sizeof(gt), "%s/kitti-odometry-%s-clip/poses/%s.txt", data, c->seq, c->seq);
	snprintf(out, sizeof(out), "%s/%s.kitti", harness_tmpdir(), c->seq);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", src, "--gt", gt, "--scale", "gt",
			"--trajectory", out, "--format", "kitti", "--no-lcm", "--frontend",
			(char *)c->frontend, "--mode", (char *)c->mode, "--ba-sync", NULL, NULL, NULL,
			NULL, NULL};
	int argc = 17;
	char tracks[16];
	if (c->ate_m > 0) { /* KITTI's camera is 1.65 m above the road */
		argv[6] = "height";
		argv[argc++] = "--camera-height";
		argv[argc++] = "1.65";
	}
	if (c->tracks) {
		snprintf(tracks, sizeof(tracks), "%d", c->tracks);
		argv[argc++] = "--tracks";
		argv[argc++] = tracks;
	}
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mvod failed (%d): %s", r.status, r.err);
	struct traj_errors e;
	harness_compare(out, gt, 0, &e);
	print_message("KITTI %s %s %s (tracks %d): %d frames, rot %.4f deg/frame (max %.4f), dir %.3f deg (max %.3f), "
		      "ATE %.3f m over %.1f m\n%s",
		      c->seq, c->mode, c->frontend, c->tracks, e.n, e.rpe.rot_deg_mean, e.rpe.rot_deg_max, e.rpe.dir_deg_mean,
		      e.rpe.dir_deg_max, e.ate_m, e.length_m, r.out);
	assert_int_equal(e.n, c->frames);
	assert_true(e.rpe.rot_deg_mean < c->rot_mean);
	assert_true(e.rpe.rot_deg_max < c->rot_max);
	assert_true(e.rpe.dir_deg_mean < c->dir_mean);
	assert_true(!(c->ate_m > 0) || e.ate_m < c->ate_m);
	return e.ate_m;
}

/* The default front end (auto: klt here). Bounds about twice the measured, as orb's below. */
static void test_kitti_06(void **state)
{
	(void)state;
	/* Measured (klt, 500 tracks): rotation 0.067 deg/frame (max 0.193), direction 0.55. */
	run_clip(&(struct clip){"06", "auto", "twoview", 51, 0.13, 0.4, 1.1, 0, 0});
}

static void test_kitti_07(void **state)
{
	(void)state;
	/* Measured (klt, 500 tracks): rotation 0.041 deg/frame (max 0.126), direction 0.81. */
	run_clip(&(struct clip){"07", "auto", "twoview", 160, 0.08, 0.3, 1.6, 0, 0});
}

/* The descriptor front end (map mode's), on its own bounds. */
static void test_kitti_06_orb(void **state)
{
	(void)state;
	/*
	 * Measured: rotation 0.050 deg/frame (max 0.148), direction 0.41 deg/frame; before the
	 * refined motion and the road band (issue 12): 0.109 (max 0.264), 1.75.
	 */
	run_clip(&(struct clip){"06", "orb", "twoview", 51, 0.1, 0.3, 0.9, 0, 0});
}

static void test_kitti_07_orb(void **state)
{
	(void)state;
	/*
	 * Measured: rotation 0.040 deg/frame (max 0.494), direction 1.19 deg/frame; before the
	 * refined motion and the road band (issue 12): 0.118 (max 3.06, while the car pulls away
	 * at 9 cm per frame), 3.70.
	 */
	run_clip(&(struct clip){"07", "orb", "twoview", 160, 0.08, 1.0, 2.4, 0, 0});
}

/* Map mode, both front ends; bounds about twice the measured, as above. */
static void test_kitti_06_map(void **state)
{
	(void)state;
	/*
	 * Measured (klt): rotation 0.046 deg/frame (max 0.156), direction 0.37 (0.044, 0.30 with a
	 * keyframe on every frame under 90 % of the tracks, before mapvo.c's baseline rule for a
	 * given scale); 0.047 (max 0.166), 0.31 before the pose's refinement on the epipolar
	 * tracks (mapvo.c).
	 */
	run_clip(&(struct clip){"06", "klt", "map", 51, 0.09, 0.32, 0.6, 0, 0});
}

static void test_kitti_07_map(void **state)
{
	(void)state;
	/*
	 * Measured (klt): rotation 0.034 deg/frame (max 0.165), direction 0.85 (0.032, max 0.091,
	 * 0.74 before mapvo.c's baseline rule for keyframes with a given scale); 0.040 (max
	 * 0.113), 0.82 before the pose's refinement on the epipolar tracks (mapvo.c), and
	 * direction 1.93 while the frames held before a map (first, or rebuilt) published no
	 * translation, which counted 90 deg each: --scale gt now keeps it (mapping.c).
	 */
	run_clip(&(struct clip){"07", "klt", "map", 160, 0.065, 0.2, 1.5, 0, 0});
}

static void test_kitti_06_map_orb(void **state)
{
	(void)state;
	/*
	 * Measured: rotation 0.056 deg/frame (max 0.157), direction 0.55; 0.103 (max 0.776), 1.29
	 * before the pose's refinement on every descriptor match with the last frame (mapvo.c,
	 * track_orb), so these bounds catch its loss; before issue 12's refined two-view motion and
	 * road band: 0.190 (max 0.834), 2.83.
	 */
	run_clip(&(struct clip){"06", "orb", "map", 51, 0.12, 0.35, 1.1, 0, 0});
}

/*
 * A map built while the car pulls away from a rotation 3.25 deg wrong was tracked for 35
 * frames at 40-120 deg of direction error (direction 17.4 deg/frame, rotation 0.69): mapping.c
 * now measures the pair's parallax after the rotation-only fit too. Later changes built the
 * first map from other pairs (at most 2.3 times the rotation-only parallax): the check no longer
 * acts on this run (the same numbers without it); test_kitti_07_map_orb_height below is its test.
 */
static void test_kitti_07_map_orb(void **state)
{
	(void)state;
	/*
	 * Measured: rotation 0.045 deg/frame (max 0.239), direction 1.10; 0.098 (max 0.456), 2.52
	 * before the pose's refinement on every descriptor match with the last frame (mapvo.c,
	 * track_orb); 3.06 while the frames
	 * held before the first map published no translation (90 deg each); before issue 12's
	 * refined two-view motion and road band: 0.154 (max 3.25), 4.53; before the parallax
	 * check: 0.694 (max 8.17), 17.4.
	 */
	run_clip(&(struct clip){"07", "orb", "map", 160, 0.1, 0.5, 2.2, 0, 0});
}

/*
 * The same clip at --scale height reaches mapping.c's parallax check (INIT_MAX_PARALLAX_RATIO)
 * where the ground-truth scale no longer does: the map is lost near frame 30 and the pair
 * (30, 31) triangulates 584 points at 32.1 px where the rotation-only fit left 1.82 (17.6
 * times). The check refuses it and the map is rebuilt from (30, 32) at 5.3 px (1.5 times).
 * Only this draw reaches it: at --features 1600, 1800, 2200 or 2400 (and at --scale gt or
 * auto) every pair built had at most 3.0 times.
 */
static void test_kitti_07_map_orb_height(void **state)
{
	(void)state;
	/*
	 * Measured: rotation 0.087 deg/frame (max 2.493), direction 2.14, ATE 1.935 m; without
	 * the check (the pair's map built and tracked): 0.310 (max 2.554), 17.97, 22.18 m. The
	 * bounds are about twice the measured; the maximum rotation tells the two apart by nothing.
	 */
	run_clip(&(struct clip){"07", "orb", "map", 160, 0.17, 5.0, 4.3, 4.0, 0});
}

/*
 * Map mode's camera height on KLT, the default's: the road band's tracks from the last frame
 * triangulated with the map's own step (mapscale.c, pair_ratio). The height over the map's
 * points in the band reads the map's unit 3.5 % long on this clip (its points and its PnP
 * motion disagree). One run of 51 frames cannot tell the two apart: any change to the tracks
 * moves its SE(3) ATE by chance, so the bound is on the mean of --tracks 480, 500 and 520.
 * Measured: 0.403 / 0.202 / 0.184 m (mean 0.263) with FAST on the pyramid's level 1 (klt.c);
 * 0.217 / 0.309 / 0.346 m (0.291) on level 0, 0.263 / 0.570 / 0.155 m (0.329) on level 1 at
 * threshold 20. The map's points instead: 0.940 / 0.144 / 0.546 m (0.543), 0.56-0.68 m on
 * level 0, 0.608 / 0.729 / 0.399 m (0.579) on level 1 at 20: one draw of it can beat the
 * right method's. 0.45 m lies between the means; each run stays under 1 m (17.6 m when no
 * height is measured, as below). Rotation 0.054 deg/frame (max 0.186), direction 0.44 at
 * 500 tracks.
 */
static void test_kitti_06_map_height(void **state)
{
	(void)state;
	double ate = 0;
	for (int tracks = 480; tracks <= 520; tracks += 20)
		ate += run_clip(&(struct clip){"06", "klt", "map", 51, 0.1, 0.3, 0.75, 1.0, tracks}) / 3;
	print_message("KITTI 06 map klt height: mean ATE %.3f m over 3 track caps\n", ate);
	assert_true(ate < 0.45);
}

/*
 * --scale height on ORB features: ORB's 2000 strongest corners left KITTI 06's road bare, no
 * height was ever measured and every pose stayed at the origin (held for want of a first
 * scale: direction 90 deg a frame, ATE 17.6 m). A third of them now come from the road band.
 */
static void test_kitti_06_orb_height(void **state)
{
	(void)state;
	/*
	 * Measured: rotation 0.052 deg/frame (max 0.148), direction 0.44, ATE 0.596 m; before
	 * issue 12's refined two-view motion: 0.089 (max 0.256), 0.64, 0.383 m (its Sim(3) ATE
	 * 0.365 -> 0.176 m: the refined steps hold their scale better, the height's bias moved).
	 */
	run_clip(&(struct clip){"06", "orb", "twoview", 51, 0.11, 0.3, 0.9, 0.8, 0});
}

/* The clip in the standard layout: kitti: finds poses/07.txt beside sequences/07 itself. */
static void test_kitti_07_own_ground_truth(void **state)
{
	(void)state;
	const char *data = getenv("MVOD_DATA");
	char uri[600], gt_path[600], from[4096], err[512];
	snprintf(uri, sizeof(uri), "kitti:%s/kitti-odometry-07-clip/sequences/07", data);
	snprintf(gt_path, sizeof(gt_path), "%s/kitti-odometry-07-clip/poses/07.txt", data);
	struct mvod_source *src;
	struct mvod_traj gt, want;
	assert_int_equal(mvod_source_open(uri, &src, err, sizeof(err)), 0);
	assert_int_equal(mvod_source_ground_truth(src, &gt, from, sizeof(from), err, sizeof(err)), 0);
	assert_non_null(strstr(from, "kitti-odometry-07-clip/poses/07.txt"));
	assert_int_equal(mvod_traj_load(gt_path, &want, err, sizeof(err)), 0);
	assert_int_equal(gt.n, 160);
	assert_int_equal(want.n, 160);
	assert_memory_equal(gt.pose, want.pose, sizeof(*gt.pose) * 160);
	mvod_traj_free(&gt);
	mvod_traj_free(&want);
	mvod_source_close(src);
}

int main(void)
{
	const char *data = getenv("MVOD_DATA");
	struct stat st;
	if (!data || stat(data, &st) != 0) {
		printf("../shared/data is absent: skipping the KITTI tests\n");
		return EXIT_SKIP;
	}
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_kitti_06),
		cmocka_unit_test(test_kitti_07),
		cmocka_unit_test(test_kitti_06_orb),
		cmocka_unit_test(test_kitti_07_orb),
		cmocka_unit_test(test_kitti_06_map),
		cmocka_unit_test(test_kitti_07_map),
		cmocka_unit_test(test_kitti_06_map_orb),
		cmocka_unit_test(test_kitti_07_map_orb),
		cmocka_unit_test(test_kitti_07_map_orb_height),
		cmocka_unit_test(test_kitti_06_map_height),
		cmocka_unit_test(test_kitti_06_orb_height),
		cmocka_unit_test(test_kitti_07_own_ground_truth),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
