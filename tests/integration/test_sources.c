/*
 * Sources that say what they did (issue 10): the real binary on videos made with mkvideo
 * (variable frame rate, a resolution change) and on image folders with bad frames, odd names
 * and a times.txt that goes backwards.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>
#include <math.h>

#include "harness.h"

static char seq[256], calib[300], traj[300];

/* A 64x48 pinhole camera for mkvideo's frames (fx 0.9 width, as mvod-synth's default). */
static const char *small_calib =
	"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", "
	"\"image_size\": [%d, %d], \"K\": [[%g, 0, %g], [0, %g, %g], [0, 0, 1]], "
	"\"distortion\": []}\n";

static int setup(void **state)
{
	(void)state;
	snprintf(seq, sizeof(seq), "%s/seq", harness_tmpdir());
	harness_synth(seq, "forward", 8, "png", "--size", "160x120", NULL);
	snprintf(calib, sizeof(calib), "%s/calib.json", seq);
	snprintf(traj, sizeof(traj), "%s/out.tum", harness_tmpdir());
	return 0;
}

static void write_calib(const char *path, int w, int h)
{
	char text[512];
	snprintf(text, sizeof(text), small_calib, w, h, 0.9 * w, (w - 1) / 2.0, 0.9 * w,
		 (h - 1) / 2.0);
	harness_write_file(path, text);
}

/* Runs mvod on source (with calib and a TUM trajectory); returns the result. */
static void run_mvod(const char *source, const char *calib_path, struct run_result *r)
{
	unlink(traj);
	char *argv[] = {(char *)harness_bin("MVOD"), "--no-lcm", "--source", (char *)source,
			"--calib", (char *)calib_path, "--trajectory", traj, NULL};
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited)
		fail_msg("killed by signal %d: %s", r->status, r->err);
}

/* mkvideo OUT CODEC then one WxH@MS per frame. */
static void mkvideo(const char *out, const char *codec, int n, const char *const *frames)
{
	char *argv[128] = {(char *)harness_bin("MVOD_MKVIDEO"), (char *)out, (char *)codec};
	assert_true(n < 120);
	for (int i = 0; i < n; i++)
		argv[3 + i] = (char *)frames[i];
	argv[3 + n] = NULL;
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mkvideo failed: %s", r.err);
}

/* mvod on 60 frames made by mkvideo as name, with a 64x48 calibration. */
static void run_video(const char *name, const char *codec, const char *const *frames,
		      struct run_result *r)
{
	char video[300], src[310], cal[300];
	snprintf(video, sizeof(video), "%s/%s", harness_tmpdir(), name);
	snprintf(src, sizeof(src), "file:%s", video);
	snprintf(cal, sizeof(cal), "%s/small.json", harness_tmpdir());
	mkvideo(video, codec, 60, frames);
	write_calib(cal, 64, 48);
	run_mvod(src, cal, r);
}

/*
 * Frames 20 ms and 200 ms apart in turn: the container's average rate is then 50 fps, so its
 * 6.6 s announce 330 frames for the 60 there are (OpenCV's reader took the 1 kHz time base's
 * rate: 6600). The file is whole: every frame comes out, at its container time, and the run
 * succeeds.
 */
static void test_variable_frame_rate(void **state)
{
	(void)state;
	static char spec[60][32];
	const char *frames[60];
	long t = 0;
	for (int i = 0; i < 60; i++) {
		t += i % 10 < 5 ? 20 : 200;
		snprintf(spec[i], sizeof(spec[i]), "64x48@%ld", t);
		frames[i] = spec[i];
	}
	struct run_result r;
	run_video("vfr.mkv", "ffv1", frames, &r);
	if (r.status != 0 || !strstr(r.out, "mvod: 60 frames"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
	struct mvod_traj tr;
	char err[256];
	assert_int_equal(mvod_traj_load(traj, &tr, err, sizeof(err)), 0);
	assert_int_equal(tr.n, 60);
	/* Container times from the stream's start (the first frame's 20 ms is 0); 1 us of rounding. */
	assert_true(fabs(tr.t[5] - tr.t[4] - 0.200) < 1e-6);
	assert_true(fabs(tr.t[59] - tr.t[0] - 6.580) < 1e-6);
	mvod_traj_free(&tr);
}

/*
 * 30 frames of 64x48 then 30 of 96x72 in one MPEG-2 stream: frames of the second size are
 * skipped, said once, and counted by reason. FFmpeg 5.1's MPEG-2 decoder delivers 59 of the 60
 * frames: it starts over at the new sequence header and the 64x48 frame it held back (its
 * one-frame output delay) is lost, so 29 frames go out and all 30 of 96x72 are skipped. (The
 * OpenCV reader before video.c lost the last frame instead and, judging sizes from packets,
 * handed out the first 96x72 frame squeezed into 64x48 as frame 29.)
 */
static void test_video_resolution_change(void **state)
{
	(void)state;
	static char spec[60][32];
	const char *frames[60];
	for (int i = 0; i < 60; i++) {
		snprintf(spec[i], sizeof(spec[i]), "%s@%d", i < 30 ? "64x48" : "96x72", i * 40);
		frames[i] = spec[i];
	}
	struct run_result r;
	run_video("resize.ts", "mpeg2video", frames, &r);
	if (r.status != 0 || !strstr(r.out, "mvod: 29 frames") ||
	    !strstr(r.out, "30 skipped: 30 of another size") ||
	    !strstr(r.err, "frame 29 is of another size (the sequence is 64x48)"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
	assert_int_equal(harness_traj_lines(traj), 29);
	/* The last frame out is the last 64x48 one the decoder kept, 28 x 40 ms in. */
	struct mvod_traj tr;
	char err[256];
	assert_int_equal(mvod_traj_load(traj, &tr, err, sizeof(err)), 0);
	assert_true(fabs(tr.t[28] - tr.t[0] - 1.120) < 1e-6);
	mvod_traj_free(&tr);
}

/* A copy of the synthetic image folder, into dir, with times.txt as given (NULL: the same). */
static void copy_images(const char *dir, const char *times)
{
	char cmd[1024];
	snprintf(cmd, sizeof(cmd), "rm -rf '%s' && cp -r '%s/images' '%s'", dir, seq, dir);
	assert_int_equal(system(cmd), 0);
	if (times) {
		snprintf(cmd, sizeof(cmd), "%s/times.txt", dir);
		harness_write_file(cmd, times);
	}
}

/*
 * Bad frames in a folder: one corrupt, one of another size (a frame of a 64x48 sequence),
 * one a 3 GB sparse file. Each is skipped and counted by its reason; the huge one is refused
 * before a byte of it is read (the run stays far below 3 GB: it would fail under the test's
 * memory otherwise, and its buffer would be kept).
 */
static void test_bad_frames_counted(void **state)
{
	(void)state;
	char dir[300], path[400], other[300], src[310], cmd[1024];
	snprintf(dir, sizeof(dir), "%s/bad", harness_tmpdir());
	copy_images(dir, NULL);
	snprintf(path, sizeof(path), "%s/000002.png", dir);
	harness_write_file(path, "not a png\n");
	snprintf(other, sizeof(other), "%s/other", harness_tmpdir());
	harness_synth(other, "forward", 1, "png", "--size", "64x48", NULL);
	snprintf(cmd, sizeof(cmd), "cp '%s/images/000000.png' '%s/000004.png'", other, dir);
	assert_int_equal(system(cmd), 0);
	snprintf(path, sizeof(path), "%s/000006.png", dir);
	snprintf(cmd, sizeof(cmd), "truncate -s 3G '%s'", path);
	assert_int_equal(system(cmd), 0);
	snprintf(src, sizeof(src), "images:%s", dir);
	struct run_result r;
	run_mvod(src, calib, &r);
	if (r.status != 0 || !strstr(r.out, "mvod: 5 frames") ||
	    !strstr(r.out, "3 skipped: 1 corrupt or not an image, 1 too large a file, 1 of "
			   "another size"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
	assert_int_equal(harness_traj_lines(traj), 5);
}

/* times.txt must increase: a step back is refused with the file and the line. */
static void test_times_backwards(void **state)
{
	(void)state;
	char dir[300], src[310];
	snprintf(dir, sizeof(dir), "%s/back", harness_tmpdir());
	copy_images(dir, "0.0\n0.1\n0.2\n0.15\n0.4\n0.5\n0.6\n0.7\n");
	snprintf(src, sizeof(src), "images:%s", dir);
	struct run_result r;
	run_mvod(src, calib, &r);
	if (r.status != 1 || !strstr(r.err, "times.txt line 4: 0.150000 s is not after the line "
					    "before (0.200000 s)"))
		fail_msg("exit %d: %s", r.status, r.err);
	assert_int_not_equal(access(traj, F_OK), 0);
}

/*
 * Names that are timestamps sort as numbers: 1.15 before 1.2 and 1.3 (version sort compares
 * 15 with 2 and 3 and puts 1.15, 1.25 and 1.35 last). The frame named 1.3 is the 6th in
 * numeric order (frame 5), the 4th (frame 3) in version order.
 */
static void test_decimal_names(void **state)
{
	(void)state;
	static const char *const names[8] = {"1.05", "1.1", "1.15", "1.2", "1.25", "1.3", "1.35",
					     "1.4"};
	char dir[300], from[400], to[400], src[310];
	snprintf(dir, sizeof(dir), "%s/decimal", harness_tmpdir());
	copy_images(dir, "1.05\n1.1\n1.15\n1.2\n1.25\n1.3\n1.35\n1.4\n");
	for (int i = 0; i < 8; i++) {
		snprintf(from, sizeof(from), "%s/%06d.png", dir, i);
		snprintf(to, sizeof(to), "%s/%s.png", dir, names[i]);
		assert_int_equal(rename(from, to), 0);
	}
	/* The frame named 1.3 is corrupt: its place in the order is in the warning. */
	snprintf(to, sizeof(to), "%s/1.3.png", dir);
	harness_write_file(to, "not a png\n");
	snprintf(src, sizeof(src), "images:%s", dir);
	struct run_result r;
	run_mvod(src, calib, &r);
	if (r.status != 0 || !strstr(r.err, "frame 5 is corrupt"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_variable_frame_rate),
		cmocka_unit_test(test_video_resolution_change),
		cmocka_unit_test(test_bad_frames_counted),
		cmocka_unit_test(test_times_backwards),
		cmocka_unit_test(test_decimal_names),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
