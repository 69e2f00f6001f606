/*
 * Datasets as sources: one mvod-synth rendering written as plain images, as EuRoC MAV and as
 * TUM RGB-D (and re-laid as TUM monoVO and KITTI here), read back through euroc:, tum: and
 * kitti:. The frames are the same PNGs, so the trajectories must be the same to the last
 * printed digit; the ground truth each dataset carries must be mvod-synth's camera poses
 * (gt.tum), whatever world and body frame the layout stores them in; bad input is one message
 * naming the file and the line.
 */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"
#include "capture/euroc_sensor.h"
#include "mvod/calib.h"
#include "mvod/capture.h"

/* 20 frames of the turn path at 320x240: the camera yaws, so a body frame shows. ~1 s each. */
#define FRAMES 20
/* mvod-synth's dataset clocks (tools/synth/datasets.hpp). */
#define EUROC_START_NS 1403636579763555584LL
#define TUM_START_US 1305031102175304LL
#define PERIOD_US 100000 /* mvod-synth's default 10 Hz */
/* mvod-synth's KITTI raw clock: 2011-09-26 13:02:25.964389445, read as UTC, in whole us. */
#define KITTI_RAW_START_US 1317042145964389LL
#define KITTI_RAW_DRIVE "2011_09_26/2011_09_26_drive_0001_sync"

static char png[256], euroc[256], tum[256], pin[256], kraw[256];

static void synth(const char *dir, const char *format)
{
	harness_synth(dir, "turn", FRAMES, format, "--size", "320x240", "--distortion",
		      "-0.2,0.05,0.001,-0.001", NULL);
}

/* The same street through no lens: KITTI raw's frames are rectified. */
static void synth_pinhole(const char *dir, const char *format)
{
	harness_synth(dir, "turn", FRAMES, format, "--size", "320x240", NULL);
}

static int setup(void **state)
{
	(void)state;
	snprintf(png, sizeof(png), "%s", harness_tmp_path("png"));
	snprintf(euroc, sizeof(euroc), "%s", harness_tmp_path("euroc"));
	snprintf(tum, sizeof(tum), "%s", harness_tmp_path("tum"));
	snprintf(pin, sizeof(pin), "%s", harness_tmp_path("pin"));
	snprintf(kraw, sizeof(kraw), "%s", harness_tmp_path("kraw"));
	synth(png, "png");
	synth(euroc, "euroc");
	synth(tum, "tum");
	synth_pinhole(pin, "png");
	synth_pinhole(kraw, "kitti-raw");
	return 0;
}

/* mvod on source (calib may be NULL) writing a TUM trajectory to out; must succeed. */
static void run_to(const char *source, const char *calib, const char *out)
{
	char *argv[12] = {(char *)harness_bin("MVOD"), "--source", (char *)source, "--trajectory",
			  (char *)out, "--no-lcm", NULL};
	if (calib) {
		argv[6] = "--calib";
		argv[7] = (char *)calib;
		argv[8] = NULL;
	}
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod --source %s failed (%d): %s", source, r.status, r.err);
}

/*
 * The trajectory of source is the images: run's of the rendering in dir, pose for pose, byte
 * for byte; its times are start_us + i * PERIOD_US, printed in seconds with 6 decimals (no
 * digit lost to a double).
 */
static void expect_same_as(const char *dir, const char *source, const char *calib,
			   const char *name, long long start_us)
{
	char images[300], calib_png[300], out_png[300];
	snprintf(images, sizeof(images), "images:%s/images", dir);
	snprintf(calib_png, sizeof(calib_png), "%s/calib.json", dir);
	snprintf(out_png, sizeof(out_png), "%s/est.tum", dir);
	if (access(out_png, F_OK) != 0)
		run_to(images, calib_png, out_png);
	const char *out = harness_tmp_path(name);
	run_to(source, calib, out);
	static char a[65536], b[65536];
	harness_read_file(out, a, sizeof(a));
	harness_read_file(out_png, b, sizeof(b));
	int lines = 0;
	for (char *p = a, *q = b; *p && *q; lines++) {
		char stamp[32];
		long long us = start_us + (long long)lines * PERIOD_US;
		snprintf(stamp, sizeof(stamp), "%lld.%06lld ", us / 1000000, us % 1000000);
		if (strncmp(p, stamp, strlen(stamp)) != 0)
			fail_msg("%s line %d: expected time %s, got \"%.24s\"", name, lines + 1, stamp, p);
		char *pe = strchr(p, '\n'), *qe = strchr(q, '\n');
		assert_non_null(pe);
		assert_non_null(qe);
		/* The pose columns, after each line's time. */
		char *pp = strchr(p, ' '), *qp = strchr(q, ' ');
		if (pe - pp != qe - qp || memcmp(pp, qp, (size_t)(pe - pp)) != 0)
			fail_msg("%s line %d differs from the images run:\n%.*s\n%.*s", name, lines + 1,
				 (int)(pe - p), p, (int)(qe - q), q);
		p = pe + 1;
		q = qe + 1;
	}
	assert_int_equal(lines, FRAMES);
	assert_int_equal(harness_count_lines(out), FRAMES);
}

static void expect_same_as_images(const char *source, const char *calib, const char *name,
				  long long start_us)
{
	expect_same_as(png, source, calib, name, start_us);
}

static void test_euroc_same_as_images(void **state)
{
	(void)state;
	char uri[300];
	/* No --calib: sensor.yaml's intrinsics and distortion are calib.json's. */
	snprintf(uri, sizeof(uri), "euroc:%s", euroc);
	/* 1403636579763555584 ns is ...763556 us, rounded. */
	expect_same_as_images(uri, NULL, "euroc.tum", (EUROC_START_NS + 500) / 1000);
}

static void test_tum_same_as_images(void **state)
{
	(void)state;
	char uri[300], calib[300];
	snprintf(uri, sizeof(uri), "tum:%s", tum);
	snprintf(calib, sizeof(calib), "%s/calib.json", tum);
	expect_same_as_images(uri, calib, "tum.tum", TUM_START_US);
}

/* The monoVO layout, around the same PNGs: times.txt "id t exposure", camera.txt RadTan. */
static void test_tum_mono_same_as_images(void **state)
{
	(void)state;
	const char *dir = harness_tmp_path("mono");
	char path[600], images[300], text[4096] = "", calib_png[300];
	assert_int_equal(mkdir(dir, 0755), 0);
	snprintf(images, sizeof(images), "%s/images", png);
	snprintf(path, sizeof(path), "%s/images", dir);
	assert_int_equal(symlink(images, path), 0);
	for (int i = 0; i < FRAMES; i++)
		snprintf(text + strlen(text), sizeof(text) - strlen(text), "%06d %.6f 10.0\n", i,
			 i * PERIOD_US / 1e6);
	snprintf(path, sizeof(path), "%s/times.txt", dir);
	harness_write_file(path, text);
	struct mvod_camera cam;
	char err[512];
	snprintf(calib_png, sizeof(calib_png), "%s/calib.json", png);
	assert_int_equal(mvod_calib_load(calib_png, &cam, err, sizeof(err)), 0);
	snprintf(text, sizeof(text), "RadTan %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n"
		 "%d %d\ncrop\n%d %d\n", cam.fx, cam.fy, cam.cx, cam.cy, cam.dist[0], cam.dist[1],
		 cam.dist[2], cam.dist[3], cam.width, cam.height, cam.width, cam.height);
	snprintf(path, sizeof(path), "%s/camera.txt", dir);
	harness_write_file(path, text);
	char uri[300];
	snprintf(uri, sizeof(uri), "tum:%s", dir);
	expect_same_as_images(uri, NULL, "mono.tum", 0);
}

static double rot_diff_deg(const double A[9], const double B[9])
{
	double R[9];
	mvod_mat3_mul_at(A, B, R);
	return mvod_rot_angle(R) * 180 / M_PI;
}

/*
 * The ground truth uri carries is gt.tum (mvod-synth's camera poses, first camera = world):
 * a pose for every frame at the frame's time. Bounds: gt.tum holds 9 significant digits (5e-9
 * m on these 2 m, 1e-9 rad); the dataset's 17-digit text and its compositions round at 1e-16.
 */
static void expect_gt_is_camera(const char *uri, const char *gt_tum, const char *from_name)
{
	struct mvod_source *src;
	struct mvod_traj gt, want;
	char err[512] = "", from[4096] = "";
	if (mvod_source_open(uri, &src, err, sizeof(err)) != 0)
		fail_msg("%s: %s", uri, err);
	if (mvod_source_ground_truth(src, &gt, from, sizeof(from), err, sizeof(err)) != 0)
		fail_msg("%s: %s", uri, err);
	assert_non_null(strstr(from, from_name));
	assert_int_equal(mvod_traj_load(gt_tum, &want, err, sizeof(err)), 0);
	assert_int_equal(gt.n, FRAMES);
	assert_int_equal(want.n, FRAMES);
	struct mvod_frame f;
	double dt = 0, dr = 0;
	for (int i = 0; i < gt.n; i++) {
		assert_int_equal(mvod_source_read(src, &f), 0);
		assert_true(gt.t[i] == f.utime / 1e6); /* found by the frame exactly */
		dt = fmax(dt, mvod_vec3_dist(gt.pose[i].t, want.pose[i].t));
		dr = fmax(dr, rot_diff_deg(gt.pose[i].R, want.pose[i].R));
	}
	print_message("%s: ground truth off gt.tum by %.2g m, %.2g deg at most\n", uri, dt, dr);
	assert_true(dt < 1e-7);
	assert_true(dr < 1e-6);
	mvod_traj_free(&gt);
	mvod_traj_free(&want);
	mvod_source_close(src);
}

/* Body poses of the EuRoC file relative to the first: what ignoring T_BS would give. */
static void body_poses(const char *csv, struct mvod_pose *out, int n)
{
	FILE *f = fopen(csv, "r");
	assert_non_null(f);
	char line[1024];
	struct mvod_pose first_inv;
	for (int i = 0; i < n && fgets(line, sizeof(line), f);) {
		long long ns;
		double v[7];
		if (sscanf(line, "%lld,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &ns, &v[0], &v[1], &v[2], &v[3],
			   &v[4], &v[5], &v[6]) != 8)
			continue;
		struct mvod_pose p;
		memcpy(p.t, v, sizeof(p.t));
		mvod_quat_to_rot(v + 3, p.R);
		if (i == 0)
			mvod_pose_inverse(&p, &first_inv);
		mvod_pose_compose(&first_inv, &p, &out[i++]);
	}
	fclose(f);
}

static void test_euroc_ground_truth_is_the_camera(void **state)
{
	(void)state;
	char uri[300], gt_tum[300], csv[300];
	snprintf(uri, sizeof(uri), "euroc:%s", euroc);
	snprintf(gt_tum, sizeof(gt_tum), "%s/gt.tum", euroc);
	expect_gt_is_camera(uri, gt_tum, "state_groundtruth_estimate0/data.csv");
	/* mav0 itself, and ?cam=0, name the same sequence. */
	snprintf(uri, sizeof(uri), "euroc:%s/mav0?cam=0", euroc);
	expect_gt_is_camera(uri, gt_tum, "state_groundtruth_estimate0/data.csv");
	/*
	 * The data make a wrong frame plain: the body poses themselves, relative to the first,
	 * are far from the camera's (the T_BS lever arm and the quarter turn about z).
	 */
	struct mvod_pose body[FRAMES];
	struct mvod_traj want;
	char err[512];
	snprintf(csv, sizeof(csv), "%s/mav0/state_groundtruth_estimate0/data.csv", euroc);
	body_poses(csv, body, FRAMES);
	assert_int_equal(mvod_traj_load(gt_tum, &want, err, sizeof(err)), 0);
	double worst = 0;
	for (int i = 0; i < FRAMES; i++)
		worst = fmax(worst, mvod_vec3_dist(body[i].t, want.pose[i].t));
	print_message("body poses taken for the camera's: off by up to %.3f m\n", worst);
	assert_true(worst > 0.5); /* the camera moves 2 m forward; the body's x is its left */
	mvod_traj_free(&want);
}

static void test_tum_ground_truth_is_the_camera(void **state)
{
	(void)state;
	char uri[300], gt_tum[300];
	snprintf(uri, sizeof(uri), "tum:%s", tum);
	snprintf(gt_tum, sizeof(gt_tum), "%s/gt.tum", tum);
	expect_gt_is_camera(uri, gt_tum, "groundtruth.txt");
}

/* The KITTI odometry layout around the same PNGs: ROOT/sequences/00 and ROOT/poses/00.txt. */
static void test_kitti_ground_truth_beside(void **state)
{
	(void)state;
	char seq[600], path[1400], text[512], gt_kitti[300], images[300];
	snprintf(seq, sizeof(seq), "%s/sequences/00", harness_tmp_path("kitti"));
	snprintf(path, sizeof(path), "mkdir -p '%s' '%s/../../poses'", seq, seq);
	assert_int_equal(system(path), 0);
	snprintf(images, sizeof(images), "%s/images", png);
	snprintf(path, sizeof(path), "%s/image_0", seq);
	assert_int_equal(symlink(images, path), 0);
	struct mvod_camera cam;
	char err[512];
	snprintf(path, sizeof(path), "%s/calib.json", png);
	assert_int_equal(mvod_calib_load(path, &cam, err, sizeof(err)), 0);
	snprintf(text, sizeof(text), "P0: %.17g 0 %.17g 0 0 %.17g %.17g 0 0 0 1 0\n", cam.fx,
		 cam.cx, cam.fy, cam.cy);
	snprintf(path, sizeof(path), "%s/calib.txt", seq);
	harness_write_file(path, text);
	char uri[700];
	snprintf(uri, sizeof(uri), "kitti:%s", seq);
	struct mvod_source *src;
	struct mvod_traj gt;
	char from[4096];
	assert_int_equal(mvod_source_open(uri, &src, err, sizeof(err)), 0);
	/* No poses/00.txt yet: none. */
	assert_int_equal(mvod_source_ground_truth(src, &gt, from, sizeof(from), err, sizeof(err)),
			 -ENOENT);
	mvod_source_close(src);
	snprintf(gt_kitti, sizeof(gt_kitti), "%s/gt.kitti", png);
	snprintf(path, sizeof(path), "%s/../../poses/00.txt", seq);
	assert_int_equal(symlink(gt_kitti, path), 0);
	assert_int_equal(mvod_source_open(uri, &src, err, sizeof(err)), 0);
	assert_int_equal(mvod_source_ground_truth(src, &gt, from, sizeof(from), err, sizeof(err)),
			 0);
	assert_non_null(strstr(from, "/poses/00.txt"));
	assert_int_equal(gt.n, FRAMES);
	assert_int_equal(gt.format, MVOD_TRAJ_KITTI);
	mvod_traj_free(&gt);
	mvod_source_close(src);
}

/* The published header of state_groundtruth_estimate0/data.csv (MH_01_easy's, LF lines). */
static const char euroc_gt_header[] =
	"#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
	"q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
	"b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
	"b_a_RS_S_z [m s^-2]\n";

/*
 * sensor.yaml in the layout of MH_01_easy's published cam0 one (the unit test's fixture, from
 * a byte-for-byte copy: comments, T_BS's rows a line each aligned on the sign, no newline at
 * the end), with the rendering's camera and T_BS; head goes first ("" or OpenCV's line).
 */
static void published_sensor(const char *path, const char *head)
{
	struct mvod_camera c;
	struct mvod_pose bs;
	char err[512], text[4096], rows[1024] = "";
	snprintf(text, sizeof(text), "%s/mav0/cam0/sensor.yaml", euroc);
	assert_int_equal(mvod_euroc_sensor_load(text, &c, &bs, err, sizeof(err)), 0);
	for (int r = 0; r < 4; r++) {
		double v[4] = {0, 0, 0, 1};
		if (r < 3)
			v[0] = bs.R[3 * r], v[1] = bs.R[3 * r + 1], v[2] = bs.R[3 * r + 2], v[3] = bs.t[r];
		snprintf(rows + strlen(rows), sizeof(rows) - strlen(rows), "%s%.17g, %.17g, %.17g, %.17g",
			 r == 0 ? "" : v[0] < 0 ? ",\n        " : ",\n         ", v[0], v[1], v[2], v[3]);
	}
	snprintf(text, sizeof(text), "%s# General sensor definitions.\nsensor_type: camera\ncomment: "
		 "VI-Sensor cam0 (MT9M034)\n\n# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: "
		 "4\n  rows: 4\n  data: [%s]\n\n# Camera specific definitions.\nrate_hz: 20\nresolution: "
		 "[%d, %d]\ncamera_model: pinhole\nintrinsics: [%.17g, %.17g, %.17g, %.17g] #fu, fv, "
		 "cu, cv\ndistortion_model: radial-tangential\ndistortion_coefficients: [%.17g, %.17g, "
		 "%.17g, %.17g]", head, rows, c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.dist[0],
		 c.dist[1], c.dist[2], c.dist[3]);
	harness_write_file(path, text);
}

/*
 * A EuRoC folder whose sensor.yaml, data.csv (CRLF, the published header; rows ending in a
 * comma when commas) and ground-truth CSV are in the published form, around the rendering's
 * frames and poses; head as for published_sensor. Returns the euroc: URI.
 */
static const char *published_euroc(const char *name, const char *head, bool commas)
{
	static char uri[300];
	const char *dir = harness_tmp_path(name);
	char path[600], target[300], text[65536] = "#timestamp [ns],filename\r\n";
	snprintf(path, sizeof(path), "mkdir -p '%s/mav0/cam0' '%s/mav0/state_groundtruth_estimate0'",
		 dir, dir);
	assert_int_equal(system(path), 0);
	snprintf(path, sizeof(path), "%s/mav0/cam0/data", dir);
	snprintf(target, sizeof(target), "%s/mav0/cam0/data", euroc);
	assert_int_equal(symlink(target, path), 0);
	snprintf(path, sizeof(path), "%s/mav0/cam0/sensor.yaml", dir);
	published_sensor(path, head);
	for (int i = 0; i < FRAMES; i++) {
		long long ns = EUROC_START_NS + (long long)i * PERIOD_US * 1000;
		snprintf(text + strlen(text), sizeof(text) - strlen(text), "%lld,%lld.png%s\r\n", ns,
			 ns, commas ? "," : "");
	}
	snprintf(path, sizeof(path), "%s/mav0/cam0/data.csv", dir);
	harness_write_file(path, text);
	snprintf(path, sizeof(path), "%s/mav0/state_groundtruth_estimate0/data.csv", euroc);
	harness_read_file(path, text, sizeof(text));
	char *rows = strchr(text, '\n') + 1, gt[65536];
	snprintf(gt, sizeof(gt), "%s%s", euroc_gt_header, rows);
	snprintf(path, sizeof(path), "%s/mav0/state_groundtruth_estimate0/data.csv", dir);
	harness_write_file(path, gt);
	snprintf(uri, sizeof(uri), "euroc:%s", dir);
	return uri;
}

/*
 * euroc: on the files as published, and on the copy OpenCV's FileStorage readers want
 * ("%YAML:1.0" first, Kimera-VIO's instructions): the images: run, digit for digit, and the
 * rendering's ground truth.
 */
static void test_euroc_as_published(void **state)
{
	(void)state;
	char gt_tum[300];
	snprintf(gt_tum, sizeof(gt_tum), "%s/gt.tum", euroc);
	const char *uri = published_euroc("pub", "", false);
	expect_same_as_images(uri, NULL, "pub.tum", (EUROC_START_NS + 500) / 1000);
	expect_gt_is_camera(uri, gt_tum, "state_groundtruth_estimate0/data.csv");
	uri = published_euroc("pubcv", "%YAML:1.0\n", true);
	expect_same_as_images(uri, NULL, "pubcv.tum", (EUROC_START_NS + 500) / 1000);
	expect_gt_is_camera(uri, gt_tum, "state_groundtruth_estimate0/data.csv");
}

static const char *kitti_raw_uri(const char *root)
{
	static char uri[400];
	snprintf(uri, sizeof(uri), "kitti-raw:%s/" KITTI_RAW_DRIVE, root);
	return uri;
}

/* kitti-raw: reads mvod-synth's KITTI raw drive as images: reads its frames. */
static void test_kitti_raw_same_as_images(void **state)
{
	(void)state;
	expect_same_as(pin, kitti_raw_uri(kraw), NULL, "kraw.tum", KITTI_RAW_START_US);
}

/*
 * OXTS to camera 0 through the calibration: the rendering's camera poses (gt.tum), within
 * expect_gt_is_camera's bounds: the packets print 17 digits, the Mercator projection and its
 * inverse round at 1e-9 m on coordinates near 5e6 m, and mvod's nearest rotation and
 * mvod-synth's (OpenCV's SVD) agree to 1e-15.
 */
static void test_kitti_raw_ground_truth(void **state)
{
	(void)state;
	char gt_tum[300];
	snprintf(gt_tum, sizeof(gt_tum), "%s/gt.tum", kraw);
	expect_gt_is_camera(kitti_raw_uri(kraw), gt_tum, "oxts/data/NNNNNNNNNN.txt through");
}

/*
 * TUM monoVO's FOV lens: a sequence rendered through it (w = 0.9, monoVO's 0.90-0.95) and its
 * pinhole twin (the same street and path without a lens), each read by tum: from its
 * camera.txt, under mvod bench's default free scale. Measured (640x480, 80 frames of turn):
 * err_avg 0.023 and 0.023, ATE 0.017 m and 0.016 m of 8.4 m; seeds 2 and 3 gave err_avg within
 * 0.002 of the twin's and ATE within 0.025 m (the remap's bilinear resampling changes which
 * corners KLT keeps, the free-scale map follows). Bounds: err_avg within 0.01, ATE within
 * 0.05 m of the twin's. The same frames read as a pinhole (the lens ignored): err_avg 0.39.
 */
static void test_tum_mono_fov_twin(void **state)
{
	(void)state;
	const char *fov = harness_tmp_path("fov"), *twin = harness_tmp_path("twin");
	harness_synth(fov, "turn", 80, "tum-mono", "--fov", "0.9", NULL);
	harness_synth(twin, "turn", 80, "tum-mono", NULL);
	double e[3][2];
	const char *dirs[3] = {fov, twin, fov};
	for (int i = 0; i < 3; i++) {
		char uri[300], gt[300], calib[300], row[4096];
		const char *csv = harness_tmp_path(i == 0 ? "fov.csv" : i == 1 ? "twin.csv" : "nolens.csv");
		snprintf(uri, sizeof(uri), "tum:%s", dirs[i]);
		snprintf(gt, sizeof(gt), "%s/gt.kitti", dirs[i]);
		snprintf(calib, sizeof(calib), "%s/calib.json", twin);
		char *argv[] = {(char *)harness_bin("MVOD"), "bench", "--source", uri, "--gt", gt,
				"--csv", (char *)csv, i == 2 ? "--calib" : NULL, calib, NULL};
		struct run_result r;
		assert_int_equal(harness_run(argv, &r), 0);
		if (r.status != 0)
			fail_msg("mvod bench --source %s (%d): %s", uri, r.status, r.err);
		harness_read_file(csv, row, sizeof(row));
		/* The row after the header: err_avg is the 9th column, ATE m the 14th. */
		const char *c = strchr(row, '\n') + 1;
		for (int k = 0; k < 13; k++) {
			if (k == 8)
				e[i][0] = atof(c);
			c = strchr(c, ',') + 1;
		}
		e[i][1] = atof(c);
	}
	print_message("err_avg, ATE m: FOV %.3f %.3f, pinhole twin %.3f %.3f, lens ignored %.3f "
		      "%.3f\n", e[0][0], e[0][1], e[1][0], e[1][1], e[2][0], e[2][1]);
	assert_true(fabs(e[0][0] - e[1][0]) <= 0.01);
	assert_true(e[0][1] <= e[1][1] + 0.05);
	assert_true(e[2][0] > 0.2);
}

/* The freiburg1/2/3 folders get the intrinsics TUM publishes; others get none. */
static void test_tum_freiburg_defaults(void **state)
{
	(void)state;
	const char *dir = harness_tmp_path("rgbd_dataset_freiburg1_synth");
	char path[600], text[256], uri[600];
	assert_int_equal(mkdir(dir, 0755), 0);
	snprintf(text, sizeof(text), "# timestamp filename\n1.0 ../tum/rgb/%lld.%06lld.png\n",
		 TUM_START_US / 1000000, TUM_START_US % 1000000);
	snprintf(path, sizeof(path), "%s/rgb.txt", dir);
	harness_write_file(path, text);
	snprintf(uri, sizeof(uri), "tum:%s", dir);
	struct mvod_source *src;
	struct mvod_camera cam;
	char err[512];
	assert_int_equal(mvod_source_open(uri, &src, err, sizeof(err)), 0);
	assert_int_equal(mvod_source_camera(src, &cam), 0);
	assert_true(cam.fx == 517.3 && cam.fy == 516.5 && cam.cx == 318.6 && cam.cy == 255.3);
	assert_int_equal(cam.n_dist, 5);
	assert_true(cam.dist[0] == 0.2624 && cam.dist[4] == 1.1633);
	mvod_source_close(src);
	/* The synthetic folder is no freiburg one: --calib is needed. */
	snprintf(uri, sizeof(uri), "tum:%s", tum);
	assert_int_equal(mvod_source_open(uri, &src, err, sizeof(err)), 0);
	assert_int_equal(mvod_source_camera(src, &cam), -ENOENT);
	mvod_source_close(src);
}

/* --- bad input: one message naming the file and the line --- */

/* "NS,NS.png" for frame i of the EuRoC rendering, then a newline. */
static void euroc_row(char *buf, size_t len, int i)
{
	long long ns = EUROC_START_NS + (long long)i * PERIOD_US * 1000;
	snprintf(buf, len, "%lld,%lld.png\n", ns, ns);
}

/*
 * euroc:DIR for a sequence around the rendering's frames: sensor.yaml is the rendering's with
 * from replaced by to (both NULL: as it is), data.csv is csv (NULL: the rendering's), and the
 * ground truth gt (NULL: none).
 */
static const char *bad_euroc(const char *from, const char *to, const char *csv, const char *gt)
{
	static char uri[300];
	const char *dir = harness_tmp_path("bad_euroc");
	char path[600], text[8192], target[300], *at;
	snprintf(path, sizeof(path), "mkdir -p '%s/mav0/cam0' '%s/mav0/state_groundtruth_estimate0'",
		 dir, dir);
	assert_int_equal(system(path), 0);
	snprintf(path, sizeof(path), "%s/mav0/cam0/data", dir);
	snprintf(target, sizeof(target), "%s/mav0/cam0/data", euroc);
	if (access(path, F_OK) != 0)
		assert_int_equal(symlink(target, path), 0);
	snprintf(path, sizeof(path), "%s/mav0/cam0/sensor.yaml", euroc);
	harness_read_file(path, text, sizeof(text));
	if (from && (at = strstr(text, from))) {
		char rest[8192];
		snprintf(rest, sizeof(rest), "%s", at + strlen(from));
		snprintf(at, sizeof(text) - (size_t)(at - text), "%s%s", to, rest);
	}
	snprintf(path, sizeof(path), "%s/mav0/cam0/sensor.yaml", dir);
	harness_write_file(path, text);
	snprintf(path, sizeof(path), "%s/mav0/cam0/data.csv", euroc);
	harness_read_file(path, text, sizeof(text));
	snprintf(path, sizeof(path), "%s/mav0/cam0/data.csv", dir);
	harness_write_file(path, csv ? csv : text);
	snprintf(path, sizeof(path), "%s/mav0/state_groundtruth_estimate0/data.csv", dir);
	unlink(path);
	if (gt)
		harness_write_file(path, gt);
	snprintf(uri, sizeof(uri), "euroc:%s", dir);
	return uri;
}

static void test_euroc_bad_frames(void **state)
{
	(void)state;
	char csv[512] = "#timestamp [ns],filename\n", row[128];
	euroc_row(row, sizeof(row), 0);
	strcat(csv, row);
	/* A row naming a file that is not there. */
	char missing[512];
	snprintf(missing, sizeof(missing), "%s%lld,missing.png\n", csv, EUROC_START_NS + 100000000LL);
	harness_source_open_fails(bad_euroc(NULL, NULL, missing, NULL), -ENOENT,
				  "data.csv line 3 names");
	harness_source_open_fails(bad_euroc(NULL, NULL, missing, NULL), -ENOENT, "missing.png");
	/* Time going backwards: frame 1's row, then frame 0's. */
	char back[512] = "#timestamp [ns],filename\n";
	euroc_row(row, sizeof(row), 1);
	strcat(back, row);
	euroc_row(row, sizeof(row), 0);
	strcat(back, row);
	harness_source_open_fails(bad_euroc(NULL, NULL, back, NULL), -EINVAL,
				  "data.csv line 3: time 1403636579.763555584 s is not after "
				  "1403636579.863555584 s of line 2");
	/* Seconds where nanoseconds belong. */
	harness_source_open_fails(bad_euroc(NULL, NULL, "1403636579.7635,x.png\n", NULL), -EINVAL,
				  "data.csv line 1: \"1403636579.7635,x.png\" is not \"timestamp [ns],"
				  "filename\"");
}

/*
 * cam0/data.csv as published: CRLF line ends (the EuRoC-rs crate's test_data, copied from
 * MH_01_easy, has them), and rows ending in an empty field; a third column is refused.
 */
static void test_euroc_csv_line_ends(void **state)
{
	(void)state;
	char csv[1024] = "#timestamp [ns],filename\r\n", row[128];
	for (int i = 0; i < 3; i++) {
		euroc_row(row, sizeof(row), i);
		strcpy(row + strlen(row) - 1, i == 1 ? ",\r\n" : "\r\n");
		strcat(csv, row);
	}
	struct mvod_source *src;
	struct mvod_frame f;
	char err[512] = "";
	if (mvod_source_open(bad_euroc(NULL, NULL, csv, NULL), &src, err, sizeof(err)) != 0)
		fail_msg("%s", err);
	for (int i = 0; i < 3; i++)
		assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(mvod_source_read(src, &f), -ENODATA);
	mvod_source_close(src);
	strcpy(strstr(csv, ",\r\n"), ",x\r\n");
	harness_source_open_fails(bad_euroc(NULL, NULL, csv, NULL), -EINVAL,
				  "data.csv line 3: \"1403636579863555584,1403636579863555584.\" is "
				  "not \"timestamp [ns],filename\""); /* the line's first 40 characters */
}

static void test_euroc_bad_sensor(void **state)
{
	(void)state;
	/*
	 * Lines of mvod-synth's sensor.yaml (MH_01_easy's layout): T_BS's data on 9 to 12,
	 * camera_model on 17, intrinsics on 18, distortion_model on 19.
	 */
	harness_source_open_fails(bad_euroc("camera_model: pinhole", "camera_model: omni", NULL,
					    NULL),
				  -EINVAL, "sensor.yaml line 17: camera_model \"omni\" is not one mvod "
				  "reads (pinhole)");
	harness_source_open_fails(bad_euroc("distortion_model: radial-tangential",
					    "distortion_model: fov", NULL, NULL),
				  -EINVAL, "sensor.yaml line 19: distortion_model \"fov\" is not one "
				  "mvod reads (radial-tangential, equidistant)");
	harness_source_open_fails(bad_euroc("sensor_type: camera", "sensor_type: imu", NULL, NULL),
				  -EINVAL, "sensor.yaml line 2: sensor_type \"imu\" is no camera");
	harness_source_open_fails(bad_euroc("intrinsics: [", "intrinsics: [1, ", NULL, NULL),
				  -EINVAL, "sensor.yaml line 18: intrinsics [fu, fv, cu, cv] must be a "
				  "list of 4 numbers");
	harness_source_open_fails(bad_euroc("data: [", "data: [2, ", NULL, NULL), -EINVAL,
				  "sensor.yaml line 9: T_BS data holds 17 numbers, not rows x cols = 4 x 4");
}

/* The ground truth uri carries fails with code and a message holding needle. */
static void expect_bad_gt(const char *uri, int code, const char *needle)
{
	struct mvod_source *src;
	struct mvod_traj gt;
	char err[1024] = "", from[4096];
	if (mvod_source_open(uri, &src, err, sizeof(err)) != 0)
		fail_msg("%s: %s", uri, err);
	assert_int_equal(mvod_source_ground_truth(src, &gt, from, sizeof(from), err, sizeof(err)),
			 code);
	if (!strstr(err, needle))
		fail_msg("\"%s\" does not say \"%s\"", err, needle);
	mvod_source_close(src);
}

static void test_euroc_bad_ground_truth(void **state)
{
	(void)state;
	/* Another sequence's: 7 minutes later than the frames. */
	const char *later = "#timestamp,x,y,z,w,x,y,z\n"
			    "1403637000000000000,0,0,0,1,0,0,0\n"
			    "1403637000005000000,0,0,0,1,0,0,0\n";
	const char *uri = bad_euroc(NULL, NULL, NULL, later);
	expect_bad_gt(uri, -ENODATA, "data.csv (lines 2..3, t = 1403637000.000000000 .. "
		      "1403637000.005000000 s) has no pose for any frame of");
	expect_bad_gt(uri, -ENODATA, "cam0/data.csv (lines 2..21, t = 1403636579.763555584 .. "
		      "1403636581.663555584 s)");
	/* The binary says so and stops before any frame. */
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", (char *)uri, "--no-lcm", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_int_equal(r.status, 2); /* the ground truth: an edit (--gt) fixes it */
	assert_non_null(strstr(r.err, "has no pose for any frame"));
	expect_bad_gt(bad_euroc(NULL, NULL, NULL, "1403636579763555584,0,0,0,1,0,0,0\n"
					   "1403636579763555583,0,0,0,1,0,0,0\n"),
		      -EINVAL, "data.csv line 2: time 1403636579.763555583 s is not after "
		      "1403636579.763555584 s of line 1: the poses must be in time order");
	expect_bad_gt(bad_euroc(NULL, NULL, NULL, "1403636579763555584,0,0,0,1,0,0\n"), -EINVAL,
		      "data.csv line 1: \"1403636579763555584,0,0,0,1,0,0\" is not \"timestamp "
		      "[ns], p_RS_R x, y, z [m], q_RS w, x, y, z, ...\"");
}

static void test_tum_bad_input(void **state)
{
	(void)state;
	const char *dir = harness_tmp_path("bad_tum");
	char path[600], uri[600];
	assert_int_equal(mkdir(dir, 0755), 0);
	snprintf(uri, sizeof(uri), "tum:%s", dir);
	harness_source_open_fails(uri, -ENOENT, "has neither rgb.txt (RGB-D benchmark) nor "
				  "times.txt (monoVO)");
	snprintf(path, sizeof(path), "%s/rgb.txt", dir);
	harness_write_file(path, "# timestamp filename\n1.0 ../tum/rgb/x.png\n1305031102,17 y\n");
	harness_source_open_fails(uri, -ENOENT, "rgb.txt line 2 names");
	harness_write_file(path, "# timestamp filename\n1305031102,17 rgb/a.png\n");
	harness_source_open_fails(uri, -EINVAL, "rgb.txt line 2: \"1305031102,17 rgb/a.png\" is "
				  "not \"timestamp filename\" (seconds)");
	char text[256];
	snprintf(text, sizeof(text), "1.5 ../tum/rgb/%lld.%06lld.png\n1.6 ../tum/rgb/%lld.%06lld.png\n",
		 TUM_START_US / 1000000, TUM_START_US % 1000000,
		 (TUM_START_US + PERIOD_US) / 1000000, (TUM_START_US + PERIOD_US) % 1000000);
	harness_write_file(path, text);
	snprintf(path, sizeof(path), "%s/groundtruth.txt", dir);
	harness_write_file(path, "1.4 0 0 0 0 0 0 1\n1.3 0 0 0 0 0 0 1\n");
	expect_bad_gt(uri, -EINVAL, "groundtruth.txt line 2: time 1.300000000 s is not after "
		      "1.400000000 s of line 1");
	harness_write_file(path, "1.4 0 0 0 0 0 1\n");
	expect_bad_gt(uri, -EINVAL, "groundtruth.txt line 1: \"1.4 0 0 0 0 0 1\" is not "
		      "\"timestamp tx ty tz qx qy qz qw\"");
	/* Poses 40 ms apart around the frame: no interpolation across a gap. */
	harness_write_file(path, "1.48 0 0 0 0 0 0 1\n1.52 0 0 0 0 0 0 1\n");
	expect_bad_gt(uri, -ENODATA, "has no pose for any frame");
	/*
	 * Interpolated at the frames' times: at 1.5 s halfway from the origin to z = 1 and from
	 * no turn to a quarter turn about z; at 1.6 s at z = 2 unturned. Relative to the first:
	 * 1.5 m ahead, turned back 45 degrees.
	 */
	harness_write_file(path, "1.49 0 0 0 0 0 0 1\n1.51 0 0 1 0 0 0.70710678118654752 "
			   "0.70710678118654752\n1.59 0 0 2 0 0 0 1\n1.61 0 0 2 0 0 0 1\n");
	struct mvod_source *src;
	struct mvod_traj gt;
	char err[512], from[4096];
	assert_int_equal(mvod_source_open(uri, &src, err, sizeof(err)), 0);
	assert_int_equal(mvod_source_ground_truth(src, &gt, from, sizeof(from), err, sizeof(err)), 0);
	assert_int_equal(gt.n, 2);
	assert_true(gt.t[0] == 1.5 && gt.t[1] == 1.6);
	const double ahead[3] = {0, 0, 1.5};
	/* Bounds: a few roundings of numbers near 1 (1e-16 each). */
	assert_true(mvod_vec3_dist(gt.pose[1].t, ahead) < 1e-12);
	assert_true(fabs(mvod_rot_angle(gt.pose[1].R) * 180 / M_PI - 45) < 1e-9);
	assert_true(gt.pose[1].R[1] > 0); /* R = Rz(-45 deg): its (0, 1) entry is +sin 45 */
	mvod_traj_free(&gt);
	mvod_source_close(src);
}

/* EuRoC's ground truth begins after its camera: a bench starts at the first frame with a pose. */
static void test_euroc_bench_gt_begins_later(void **state)
{
	(void)state;
	char path[300], text[65536];
	snprintf(path, sizeof(path), "%s/mav0/state_groundtruth_estimate0/data.csv", euroc);
	harness_read_file(path, text, sizeof(text));
	const char *from = text;
	for (int i = 0; i < 4; i++) /* the header and the poses of frames 0..2 */
		from = strchr(from, '\n') + 1;
	const char *uri = bad_euroc(NULL, NULL, NULL, from);
	const char *csv = harness_tmp_path("later.csv");
	char *argv[] = {(char *)harness_bin("MVOD"), "bench", "--source", (char *)uri, "--scale", "gt",
			"--csv", (char *)csv, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	/* It says which ground truth it took, and that it skipped frames 0..2. */
	if (r.status != 0 || !strstr(r.err, "state_groundtruth_estimate0/data.csv (17 poses), which "
					    "euroc:") ||
	    !strstr(r.err, "frame 0 (t = 1403636579.763556 s) comes before the ground truth"))
		fail_msg("mvod bench (%d): %s", r.status, r.err);
	harness_read_file(csv, text, sizeof(text));
	/* The frames column (8th, after mode) of the one row: frames 3..19. */
	const char *row = strchr(text, '\n') + 1;
	for (int c = 0; c < 7; c++)
		row = strchr(row, ',') + 1;
	assert_int_equal(atoi(row), FRAMES - 3);
}

/* A camera.txt mvod cannot read: the run says which line, and wants --calib. */
static void test_tum_mono_bad_camera(void **state)
{
	(void)state;
	const char *dir = harness_tmp_path("badcam");
	char path[600], uri[600], images[300];
	assert_int_equal(mkdir(dir, 0755), 0);
	snprintf(images, sizeof(images), "%s/images", png);
	snprintf(path, sizeof(path), "%s/images", dir);
	assert_int_equal(symlink(images, path), 0);
	snprintf(path, sizeof(path), "%s/times.txt", dir);
	harness_write_file(path, "000000 0.0 10\n000001 0.1 10\n");
	snprintf(path, sizeof(path), "%s/camera.txt", dir);
	harness_write_file(path, "0.5 0.66 0.5 0.5\n320 240\ncrop\n320 240\n");
	snprintf(uri, sizeof(uri), "tum:%s", dir);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", uri, "--no-lcm", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_int_equal(r.status, 2); /* the calibration: an edit (--calib) fixes it */
	if (!strstr(r.err, "camera.txt line 1: \"0.5 0.66 0.5 0.5\" is not one of DSO's lenses"))
		fail_msg("%s", r.err);
}

/* path's text with the first from replaced by to (from must be there). */
static void edit_file(const char *path, const char *from, const char *to)
{
	static char text[65536], out[65536];
	harness_read_file(path, text, sizeof(text));
	char *at = strstr(text, from);
	assert_non_null(at);
	snprintf(out, sizeof(out), "%.*s%s%s", (int)(at - text), text, to, at + strlen(from));
	harness_write_file(path, out);
}

/* Bad KITTI raw files: each refusal names the file and, where there is one, the line. */
static void test_kitti_raw_bad_files(void **state)
{
	(void)state;
	const char *bad = harness_tmp_path("badraw");
	char cmd[800], path[600], uri[400];
	snprintf(cmd, sizeof(cmd), "cp -r '%s' '%s'", kraw, bad);
	assert_int_equal(system(cmd), 0);
	snprintf(uri, sizeof(uri), "%s", kitti_raw_uri(bad));
	/* kitti: on a raw drive says which scheme reads it. */
	char kuri[400];
	snprintf(kuri, sizeof(kuri), "kitti:%s", uri + strlen("kitti-raw:"));
	harness_source_open_fails(kuri, -EINVAL, "is a KITTI raw drive (image_00/, no calib.txt): "
				  "open it as kitti-raw:");
	/* A packet of 6 values where dataformat.txt has 30: found when the ground truth is read. */
	snprintf(path, sizeof(path), "%s/" KITTI_RAW_DRIVE "/oxts/data/0000000005.txt", bad);
	harness_write_file(path, "49.01 8.42 112.8 0 0 0\n");
	expect_bad_gt(uri, -EINVAL, "oxts/data/0000000005.txt line 1: an OXTS packet is 30 numbers");
	/* 1e-10 degrees from the pole the projection puts the IMU 1.2e8 m north: no pose (traj.h). */
	harness_write_file(path, "89.9999999999 8.42 112.8 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 "
			   "0.05 0.02 4 11 6 6 6\n");
	expect_bad_gt(uri, -EINVAL, "oxts/data/0000000005.txt line 1: position (");
	/* A time that is no calendar time. */
	snprintf(path, sizeof(path), "%s/" KITTI_RAW_DRIVE "/image_00/timestamps.txt", bad);
	edit_file(path, "13:02:26.164389445", "13:02:26,164389445");
	harness_source_open_fails(uri, -EINVAL, "image_00/timestamps.txt line 3: \"2011-09-26 "
				  "13:02:26,164389445\" is not a calendar time");
	edit_file(path, "13:02:26,164389445", "13:02:26.164389445");
	/* The calibration: a key missing, or frames of another size than S_rect_00's. */
	snprintf(path, sizeof(path), "%s/2011_09_26/calib_cam_to_cam.txt", bad);
	edit_file(path, "S_rect_00: 3.200000e+02", "S_rect_00: 1.242000e+03");
	harness_source_open_fails(uri, -EINVAL, "frames are 320x240, but");
	harness_source_open_fails(uri, -EINVAL, "S_rect_00 says 1242x240");
	edit_file(path, "P_rect_00", "P_rect_01");
	harness_source_open_fails(uri, -EINVAL, "2011_09_26/calib_cam_to_cam.txt has no P_rect_00");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_euroc_same_as_images),
		cmocka_unit_test(test_tum_same_as_images),
		cmocka_unit_test(test_tum_mono_same_as_images),
		cmocka_unit_test(test_euroc_ground_truth_is_the_camera),
		cmocka_unit_test(test_euroc_as_published),
		cmocka_unit_test(test_kitti_raw_same_as_images),
		cmocka_unit_test(test_kitti_raw_ground_truth),
		cmocka_unit_test(test_kitti_raw_bad_files),
		cmocka_unit_test(test_tum_mono_fov_twin),
		cmocka_unit_test(test_tum_ground_truth_is_the_camera),
		cmocka_unit_test(test_kitti_ground_truth_beside),
		cmocka_unit_test(test_tum_freiburg_defaults),
		cmocka_unit_test(test_euroc_bad_frames),
		cmocka_unit_test(test_euroc_csv_line_ends),
		cmocka_unit_test(test_euroc_bad_sensor),
		cmocka_unit_test(test_euroc_bad_ground_truth),
		cmocka_unit_test(test_tum_bad_input),
		cmocka_unit_test(test_tum_mono_bad_camera),
		cmocka_unit_test(test_euroc_bench_gt_begins_later),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
