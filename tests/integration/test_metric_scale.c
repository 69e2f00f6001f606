/*
 * Metric scale with the real binary on mvod-synth, whose street's ground is exactly 1.6 m
 * below the camera and whose ground truth gives the exact speed: --scale height and
 * --scale external (speed through a file:// LCM log made by mvod speed-log), their fallbacks
 * (speed that stops arriving), and bad input (heights, logs of the wrong type or order).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>
#include <lcm/eventlog.h>

#include "harness.h"
#include "mvod_pose_t.h"
#include "mvod_speed_t.h"

#define FRAMES 60
static char dir[256], video[300], calib[300], gt[300];

static int setup(void **state)
{
	(void)state;
	snprintf(dir, sizeof(dir), "%s/street", harness_tmpdir());
	/* 2 m/s: 0.2 m a frame, so ground 4-10 m ahead is within 50 baselines (scale depth). */
	harness_synth(dir, "forward", FRAMES, "mkv", "--speed", "2", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(gt, sizeof(gt), "%s/gt.tum", dir);
	return 0;
}

/* mvod speed-log's log of the ground truth's speed at out; extra arguments NULL-terminated. */
static void speed_log(const char *out, ...)
{
	char *argv[16] = {(char *)harness_bin("MVOD"), "speed-log", gt, (char *)out};
	int n = 4;
	va_list ap;
	va_start(ap, out);
	for (char *a; n < 15 && (a = va_arg(ap, char *));)
		argv[n++] = a;
	va_end(ap);
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod speed-log failed (%d): %s", r.status, r.err);
}

/*
 * Logs no robot should send, made from a good one at in: out holds mvod.pose_t instead of
 * mvod.speed_t (wrong_type), or the 10th message's time goes back before the 9th's.
 */
static void spoil_log(const char *in, const char *out, bool wrong_type)
{
	lcm_eventlog_t *r = lcm_eventlog_create(in, "r"), *w = lcm_eventlog_create(out, "w");
	assert_true(r && w);
	int64_t utimes[16];
	lcm_eventlog_event_t *ev;
	for (int i = 0; (ev = lcm_eventlog_read_next_event(r)); i++) {
		mvod_speed_t m;
		uint8_t buf[256];
		assert_true(mvod_speed_t_decode(ev->data, 0, ev->datalen, &m) > 0);
		utimes[i % 16] = m.utime;
		if (!wrong_type && i == 9)
			m.utime = utimes[7];
		mvod_pose_t p = {.utime = m.utime, .orientation = {1, 0, 0, 0}};
		int len = wrong_type ? mvod_pose_t_encode(buf, 0, sizeof(buf), &p)
				     : mvod_speed_t_encode(buf, 0, sizeof(buf), &m);
		assert_true(len > 0);
		lcm_eventlog_event_t out_ev = *ev;
		out_ev.data = buf;
		out_ev.datalen = len;
		assert_int_equal(lcm_eventlog_write_event(w, &out_ev), 0);
		lcm_eventlog_free_event(ev);
	}
	lcm_eventlog_destroy(r);
	lcm_eventlog_destroy(w);
}

/*
 * mvod on the street with the scale arguments given (NULL-terminated, at most 6), poses into
 * est (a TUM file) and LCM into log; returns the run's result.
 */
static void run_mvod(struct run_result *r, const char *name, const char *a0, const char *a1,
		     const char *a2, const char *a3, const char *a4, const char *a5)
{
	char lcm[320];
	snprintf(lcm, sizeof(lcm), "file://%s/%s.lcmlog?mode=w", dir, name);
	char *argv[24] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib, "--gt",
			  gt, "--trajectory", (char *)harness_tmp_path(name), "--lcm-url", lcm};
	const char *extra[] = {a0, a1, a2, a3, a4, a5};
	int n = 11;
	for (int i = 0; i < 6 && extra[i]; i++)
		argv[n++] = (char *)extra[i];
	argv[n] = NULL;
	assert_int_equal(harness_run(argv, r), 0);
}

/* The run succeeded; its SE(3) errors (no scale alignment) against the ground truth. */
static void metric_errors(const struct run_result *r, const char *name, struct traj_errors *e)
{
	if (!r->exited || r->status != 0)
		fail_msg("mvod failed (%d): %s", r->status, r->err);
	harness_compare(harness_tmp_path(name), gt, 0, e);
	assert_int_equal(e->n, FRAMES);
	print_message("%s: ATE %.4f m over %.2f m (%.2f %%), rot %.3f deg/frame\n", name, e->ate_m,
		      e->length_m, 100 * e->ate_m / e->length_m, e->rpe.rot_deg_mean);
	/* The summary says the ATE is in metres with no scale alignment. */
	assert_non_null(strstr(r->out, "no scale alignment"));
}

/* How many of the log's frames poses have scale source src; all poses finite. */
static int count_source_in(const char *name, int frames, int src)
{
	static mvod_pose_t poses[FRAMES + 8];
	char path[320];
	snprintf(path, sizeof(path), "%s/%s.lcmlog", dir, name);
	int n = harness_poses(path, poses, FRAMES + 8), c = 0;
	assert_int_equal(n, frames);
	for (int i = 0; i < n; i++) {
		for (int k = 0; k < 3; k++)
			assert_true(isfinite(poses[i].position[k]));
		c += poses[i].scale_source == src;
	}
	return c;
}

static int count_source(const char *name, int src)
{
	return count_source_in(name, FRAMES, src);
}

/*
 * --scale height 1.6 with the two arguments given: the SE(3) ATE (no alignment) is within 3 %
 * of the path, the bound for a whole drive; a path left in any other unit is off by
 * far more.
 */
static void height_run(const char *name, const char *flag, const char *value)
{
	struct run_result r;
	struct traj_errors e;
	run_mvod(&r, name, "--scale", "height", "--camera-height", "1.6", flag, value);
	metric_errors(&r, name, &e);
	assert_true(e.ate_m < 0.03 * e.length_m);
}

static void test_height(void **state)
{
	(void)state;
	/*
	 * Two-view mode (map mode, the default: test_height_map) on KLT, auto's choice: the road
	 * band's reserved tracks (ORB's features on this street: 6.1 %). 0.45 % measured (0.053 m
	 * over 11.8 m; 0.2 % before the first three steps were held).
	 */
	height_run("height", "--mode", "twoview");
	assert_true(count_source("height", MVOD_POSE_T_SCALE_HEIGHT) > FRAMES / 2);
}

/*
 * The street seen by a camera pitched 3 deg down, with no mount in its camera file: the ground
 * normal, level at the start, learns the pitch before the first scale (scale.h,
 * MVOD_GROUND_TILTED_RUN). Measured: two-view 1.6 % (the frames held at the origin while the
 * normal learns count whole in this short path's ATE), map 0.8 % (no tilt gate in map mode;
 * 0.47 % on base7, 0.67 % with KLT's height on its band tracks: mapscale.c pair_ratio).
 * Over 80 frames of the same path, two-view: 1.1 %; 0.3 % with a normal that follows every
 * fit within 5 deg (at the cost of KITTI 07's turns); 10 % when it learnt only from fits
 * within 2 deg of level (the output held for 25 frames).
 */
static void test_height_pitched(void **state)
{
	(void)state;
	char poses[300], street[3][300];
	snprintf(poses, sizeof(poses), "%s/pitched.kitti", harness_tmpdir());
	FILE *f = fopen(poses, "w");
	assert_non_null(f);
	double p = 3 * M_PI / 180; /* camera to world: a turn of -3 deg about x, 0.2 m a frame */
	for (int i = 0; i < FRAMES; i++)
		fprintf(f, "1 0 0 0 0 %.9f %.9f 0 0 %.9f %.9f %.3f\n", cos(p), sin(p), -sin(p),
			cos(p), 0.2 * i);
	assert_int_equal(fclose(f), 0);
	strcpy(street[0], video), strcpy(street[1], calib), strcpy(street[2], gt);
	char pdir[240];
	snprintf(pdir, sizeof(pdir), "%s/pitched-street", harness_tmpdir());
	harness_synth(pdir, poses, FRAMES, "mkv", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", pdir);
	snprintf(calib, sizeof(calib), "%s/calib.json", pdir);
	snprintf(gt, sizeof(gt), "%s/gt.tum", pdir);
	height_run("pitched", "--mode", "twoview");
	height_run("pitchedmap", "--mode", "map");
	strcpy(video, street[0]), strcpy(calib, street[1]), strcpy(gt, street[2]);
}

/*
 * Map mode: the map's unit comes from the first two-view step, then mapscale.c rescales the
 * map from the road band's height at keyframes: 0.30 % measured (0.036 m over 11.8 m; 0.27 %
 * on the map's points before KLT measured on its tracks triangulated with the map's step). A map
 * left in its first unit, or rescaled with the old unit written back by BA, is off by more.
 */
static void test_height_map(void **state)
{
	(void)state;
	height_run("heightmap", "--mode", "map");
	/*
	 * With a given scale, KLT's keyframes also wait for a baseline of a tenth of the tracked
	 * points' median depth unless under 70 % of the last keyframe's tracks remain (mapvo.c,
	 * kf_due): 21 of the 60 frames measured; 42 when every frame under 90 % of them becomes
	 * one (free scale's rule), so at most 30. And the map still grows: at least 8 (a keyframe
	 * per tenth of a ~10 m median depth over the 11.8 m path).
	 */
	static mvod_pose2_t poses[FRAMES + 8];
	char path[320];
	snprintf(path, sizeof(path), "%s/heightmap.lcmlog", dir);
	int n = harness_poses2(path, poses, FRAMES + 8), kf = 0;
	assert_int_equal(n, FRAMES);
	for (int i = 0; i < n; i++)
		kf += poses[i].keyframe;
	print_message("heightmap: %d keyframes in %d frames\n", kf, n);
	assert_true(kf >= 8 && kf <= 30);
}

/*
 * Map mode, --scale height, at 14.5 m/s in KITTI's field of view (mvod-synth forward at 640x192,
 * fx 369; KITTI 06's car drives 1.45 m a frame): tracks leave the narrow image within a few
 * frames and the map is lost and rebuilt again and again (3 times in these 60 frames). Every
 * published step from the first metric one on is at least half the true one. While a new map
 * waited for parallax its steps were held at zero, and with the reference moving on, their
 * travel was lost for good: 3 zero steps here, 5.4 % of the path over 200 frames (mapping.c,
 * hold_translation). Measured 0.99-1.07 of the truth, so half is far from both.
 */
static void test_height_map_fast(void **state)
{
	(void)state;
	char fdir[240], street[3][300];
	snprintf(fdir, sizeof(fdir), "%s/fast-street", harness_tmpdir());
	harness_synth(fdir, "forward", FRAMES, "mkv", "--speed", "14.5", "--size", "640x192", "--fx",
		      "369", NULL);
	strcpy(street[0], video), strcpy(street[1], calib), strcpy(street[2], gt);
	snprintf(video, sizeof(video), "file:%s/video.mkv", fdir);
	snprintf(calib, sizeof(calib), "%s/calib.json", fdir);
	snprintf(gt, sizeof(gt), "%s/gt.tum", fdir);
	struct run_result r;
	run_mvod(&r, "fast", "--scale", "height", "--camera-height", "1.6", "--mode", "map");
	if (!r.exited || r.status != 0)
		fail_msg("mvod failed (%d): %s", r.status, r.err);
	static mvod_pose_t poses[FRAMES + 8];
	char path[320];
	snprintf(path, sizeof(path), "%s/fast.lcmlog", dir);
	assert_int_equal(harness_poses(path, poses, FRAMES + 8), FRAMES);
	double g[FRAMES][3], t;
	FILE *f = fopen(gt, "r");
	assert_non_null(f);
	for (int i = 0; i < FRAMES; i++)
		assert_int_equal(fscanf(f, "%lf %lf %lf %lf %*f %*f %*f %*f", &t, &g[i][0], &g[i][1],
					&g[i][2]),
				 4);
	fclose(f);
	/* Held at the origin until the first measurement, whose step jumps: checked after it. */
	int moved = 0, checked = 0;
	for (int i = 1; i < FRAMES; i++) {
		double d = 0, dg = 0;
		for (int k = 0; k < 3; k++) {
			d += pow(poses[i].position[k] - poses[i - 1].position[k], 2);
			dg += pow(g[i][k] - g[i - 1][k], 2);
		}
		if (!moved) {
			moved = d > 0;
			continue;
		}
		checked++;
		if (!(sqrt(d) >= 0.5 * sqrt(dg)))
			fail_msg("frame %d: step %.3f m, the truth's %.3f m", i, sqrt(d), sqrt(dg));
	}
	print_message("fast: %d steps checked\n", checked);
	assert_true(checked > FRAMES / 2);
	strcpy(video, street[0]), strcpy(calib, street[1]), strcpy(gt, street[2]);
}

/* mvod speed-log's exact speed of the street at speed.lcmlog; its file:// URL into url. */
static void exact_speed(char *url, size_t len)
{
	char log[300];
	snprintf(log, sizeof(log), "%s/speed.lcmlog", dir);
	snprintf(url, len, "file://%s?mode=r", log);
	speed_log(log, NULL);
}

/*
 * Map mode, the default: the map's unit from the odometer's distance over the map's path at
 * each keyframe (mapscale.c). Measured: 0.09 % (0.010 m over 11.8 m); 0.25 % for a map that
 * keeps the unit of its first two-view step (itself the odometer's): on this short street
 * the bound is the issue's, and test_external_speed_late is the one a map that does not
 * fuse the speed fails.
 */
static void test_external(void **state)
{
	(void)state;
	char url[320];
	exact_speed(url, sizeof(url));
	struct run_result r;
	struct traj_errors e;
	run_mvod(&r, "external", "--scale", "external", "--speed-url", url, NULL, NULL);
	metric_errors(&r, "external", &e);
	assert_true(e.ate_m < 0.01 * e.length_m);
	assert_true(count_source("external", MVOD_POSE_T_SCALE_EXTERNAL) > FRAMES * 3 / 4);
}

/* Two-view mode: each step is the odometer's difference. Measured 0.04 % (0.005 m). */
static void test_external_twoview(void **state)
{
	(void)state;
	char url[320];
	exact_speed(url, sizeof(url));
	struct run_result r;
	struct traj_errors e;
	run_mvod(&r, "external2", "--scale", "external", "--speed-url", url, "--mode", "twoview");
	metric_errors(&r, "external2", &e);
	assert_true(e.ate_m < 0.01 * e.length_m);
	assert_true(count_source("external2", MVOD_POSE_T_SCALE_EXTERNAL) > FRAMES * 3 / 4);
}

/*
 * Speed for the first 30 frames only, in mode (NULL: the default, map): from then on the
 * steps keep the last scale (two-view: from structure, map mode: the map's own unit), the
 * poses say so (scale source src), the log says why once (with needle), and the path stays
 * metric to within what the scale drifts over 30 frames (bound: fraction of the path).
 */
static void speed_stops(const char *name, const char *mode, int src, const char *needle,
			double bound)
{
	char log[300], url[320];
	snprintf(log, sizeof(log), "%s/speed30.lcmlog", dir);
	snprintf(url, sizeof(url), "file://%s?mode=r", log);
	speed_log(log, "--samples", "30", "--no-distance", NULL);
	struct run_result r;
	struct traj_errors e;
	run_mvod(&r, name, "--scale", "external", "--speed-url", url, mode ? "--mode" : NULL,
		 mode);
	metric_errors(&r, name, &e);
	assert_non_null(strstr(r.err, "no mvod.speed_t on MVOD_SPEED"));
	assert_non_null(strstr(r.err, needle));
	int ext = count_source(name, MVOD_POSE_T_SCALE_EXTERNAL);
	int kept = count_source(name, src);
	/* Frames 31-35 still extrapolate the last speed (within MVOD_SPEED_STALE_US). */
	assert_true(ext > 20 && ext <= 35);
	assert_true(kept >= 20);
	assert_true(e.ate_m < bound * e.length_m);
}

/*
 * Two-view: measured 0.08 % (5.6 % before KLT and the held start), structure alone carrying
 * the scale over the second half at 0.2 m a step. Map mode: measured 0.13 %, the map carrying
 * its unit; 2 % keeps the bound for a metric path with margin.
 */
static void test_external_speed_stops(void **state)
{
	(void)state;
	speed_stops("stops", "twoview", MVOD_POSE_T_SCALE_STRUCTURE, "scale from structure", 0.11);
	speed_stops("stopsmap", NULL, MVOD_POSE_T_SCALE_MAP, "the map keeps its last scale", 0.02);
}

/*
 * Speed that starts arriving at frame 30 (the robot's odometry started after mvod), map mode:
 * the map is built in the unit of its first step and the output held at the origin (scale
 * source none) until the first keyframe with speed, whose ratio makes the map metric at once
 * (rescaled about the origin); from then on the poses say external (31 of 60 measured), and
 * the distance from the start to the last frame is the truth's within 2 % (measured 0.08 %). A map mode that
 * did not fuse the speed would never publish a metric position (none external).
 */
static void test_external_speed_late(void **state)
{
	(void)state;
	char log[300], url[320], path[320], err[256];
	snprintf(log, sizeof(log), "%s/speedlate.lcmlog", dir);
	snprintf(url, sizeof(url), "file://%s?mode=r", log);
	speed_log(log, "--from", "30", NULL);
	struct run_result r;
	run_mvod(&r, "late", "--scale", "external", "--speed-url", url, NULL, NULL);
	if (!r.exited || r.status != 0)
		fail_msg("mvod failed (%d): %s", r.status, r.err);
	int ext = count_source("late", MVOD_POSE_T_SCALE_EXTERNAL);
	static mvod_pose_t poses[FRAMES + 8];
	snprintf(path, sizeof(path), "%s/late.lcmlog", dir);
	assert_int_equal(harness_poses(path, poses, FRAMES + 8), FRAMES);
	struct mvod_traj t;
	assert_int_equal(mvod_traj_load(gt, &t, err, sizeof(err)), 0);
	assert_int_equal(t.n, FRAMES);
	double de = 0, dg = 0;
	for (int k = 0; k < 3; k++) {
		double e = poses[FRAMES - 1].position[k] - poses[0].position[k];
		double g = t.pose[FRAMES - 1].t[k] - t.pose[0].t[k];
		de += e * e;
		dg += g * g;
	}
	mvod_traj_free(&t);
	print_message("late: %d external, distance %.3f m of %.3f m\n", ext, sqrt(de), sqrt(dg));
	assert_true(ext >= 20);
	assert_true(fabs(sqrt(de) / sqrt(dg) - 1) < 0.02);
}

/*
 * mvod-synth's stop-go path (braking to a standstill at 40 % of the time, standing until 50 %,
 * pulling away) with its exact speed, map mode: the frames standing measure nothing (the
 * odometer's zero distance rescales no map), the position stands within 1 cm (measured
 * 0.8 mm), and the path is metric within 1 %: measured 0.15 %.
 */
static void test_external_stop_go(void **state)
{
	(void)state;
	char sdir[240], log[300], url[320], street[3][300];
	strcpy(street[0], video), strcpy(street[1], calib), strcpy(street[2], gt);
	snprintf(sdir, sizeof(sdir), "%s/stop-go", harness_tmpdir());
	harness_synth(sdir, "stop-go", FRAMES, "mkv", "--speed", "2", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", sdir);
	snprintf(calib, sizeof(calib), "%s/calib.json", sdir);
	snprintf(gt, sizeof(gt), "%s/gt.tum", sdir);
	snprintf(log, sizeof(log), "%s/speed.lcmlog", sdir);
	snprintf(url, sizeof(url), "file://%s?mode=r", log);
	speed_log(log, NULL);
	struct run_result r;
	struct traj_errors e;
	run_mvod(&r, "stopgo", "--scale", "external", "--speed-url", url, NULL, NULL);
	metric_errors(&r, "stopgo", &e);
	static mvod_pose_t poses[FRAMES + 8];
	char path[320];
	snprintf(path, sizeof(path), "%s/stopgo.lcmlog", dir);
	assert_int_equal(harness_poses(path, poses, FRAMES + 8), FRAMES);
	/* Frames 24-29 of 60 (times 2.4-2.9 s of 5.9) stand at the frame 24's position. */
	double still = 0;
	for (int i = 25; i < 30; i++)
		for (int k = 0; k < 3; k++)
			still = fmax(still, fabs(poses[i].position[k] - poses[24].position[k]));
	print_message("stopgo: standing within %.4f m\n", still);
	assert_true(still < 0.01);
	assert_true(e.ate_m < 0.01 * e.length_m);
	strcpy(video, street[0]), strcpy(calib, street[1]), strcpy(gt, street[2]);
}

/* mvod exits with status, and its stderr holds needle. */
static void refused(const struct run_result *r, int status, const char *needle)
{
	if (!r->exited || r->status != status || !strstr(r->err, needle))
		fail_msg("expected exit %d with \"%s\", got %d: %s", status, needle, r->status,
			 r->err);
}

static void test_bad_heights(void **state)
{
	(void)state;
	const char *bad[] = {"-1.6", "1600", "nan", "1.6m"};
	struct run_result r;
	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		run_mvod(&r, "bad", "--scale", "height", "--camera-height", bad[i], NULL, NULL);
		refused(&r, 2, "camera-height");
	}
	run_mvod(&r, "bad", "--scale", "height", NULL, NULL, NULL, NULL);
	refused(&r, 2, "--scale height needs the camera's height");
	/* 0 is the key's "none". */
	run_mvod(&r, "bad", "--scale", "height", "--camera-height", "0", NULL, NULL);
	refused(&r, 2, "--scale height needs the camera's height");
}

static void test_bad_speed_sources(void **state)
{
	(void)state;
	struct run_result r;
	char url[320];
	run_mvod(&r, "bad", "--scale", "external", "--speed-url", "file:///nonexistent/x.lcmlog",
		 NULL, NULL);
	refused(&r, 2, "cannot read /nonexistent/x.lcmlog: No such file");
	snprintf(url, sizeof(url), "file://%s/out.lcmlog?mode=w", dir);
	run_mvod(&r, "bad", "--scale", "external", "--speed-url", url, NULL, NULL);
	refused(&r, 2, "a log to write");
	run_mvod(&r, "bad", "--scale", "external", "--speed-channel", "", NULL, NULL);
	refused(&r, 2, "speed-channel");
	/* Checked before LCM reads it: no whole event, or an absurd length LCM would trust. */
	char path[300];
	snprintf(path, sizeof(path), "%s/empty.lcmlog", dir);
	harness_write_file(path, "");
	snprintf(url, sizeof(url), "file://%s?mode=r", path);
	run_mvod(&r, "bad", "--scale", "external", "--speed-url", url, NULL, NULL);
	refused(&r, 2, "empty.lcmlog holds no whole event (0 bytes)");
	/* sync, event 0, time 0, channel length 10, data length 2^31 - 16: then the channel. */
	static const char garbage[] = "\xed\xa1\xda\x01" "\0\0\0\0\0\0\0\0" "\0\0\0\0\0\0\0\0"
				      "\0\0\0\x0a" "\x7f\xff\xff\xf0" "MVOD_SPEED" "junk";
	snprintf(path, sizeof(path), "%s/garbage.lcmlog", dir);
	FILE *f = fopen(path, "wb");
	assert_non_null(f);
	assert_int_equal(fwrite(garbage, 1, sizeof(garbage) - 1, f), sizeof(garbage) - 1);
	fclose(f);
	snprintf(url, sizeof(url), "file://%s?mode=r", path);
	run_mvod(&r, "bad", "--scale", "external", "--speed-url", url, NULL, NULL);
	refused(&r, 2, "garbage.lcmlog is corrupt at byte 0 of 42: event of");
}

/*
 * Logs of the wrong type, with a time going back, on another channel: each a warning naming
 * it, the run goes on with finite poses.
 */
static void test_bad_speed_messages(void **state)
{
	(void)state;
	static const char *const needles[] = {"are not mvod.speed_t", "not after the one before",
					      "no mvod.speed_t on MVOD_SPEED"};
	char good[300];
	snprintf(good, sizeof(good), "%s/good.lcmlog", dir);
	speed_log(good, NULL);
	for (size_t i = 0; i < 3; i++) {
		char log[300], url[320];
		snprintf(log, sizeof(log), "%s/bad%zu.lcmlog", dir, i);
		snprintf(url, sizeof(url), "file://%s?mode=r", log);
		if (i < 2)
			spoil_log(good, log, i == 0);
		else
			speed_log(log, "--no-distance", "--channel", "ELSEWHERE", NULL);
		struct run_result r;
		run_mvod(&r, "badmsg", "--scale", "external", "--speed-url", url, "--max-frames",
			 "15");
		if (!r.exited || r.status != 0 || !strstr(r.err, needles[i]))
			fail_msg("%s: exit %d, %s", needles[i], r.status, r.err);
		count_source_in("badmsg", 15, 0); /* every pose finite */
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_height),
		cmocka_unit_test(test_height_map),
		cmocka_unit_test(test_height_map_fast),
		cmocka_unit_test(test_height_pitched),
		cmocka_unit_test(test_external),
		cmocka_unit_test(test_external_twoview),
		cmocka_unit_test(test_external_speed_stops),
		cmocka_unit_test(test_external_speed_late),
		cmocka_unit_test(test_external_stop_go),
		cmocka_unit_test(test_bad_heights),
		cmocka_unit_test(test_bad_speed_sources),
		cmocka_unit_test(test_bad_speed_messages),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
