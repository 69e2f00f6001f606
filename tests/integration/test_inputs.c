/*
 * Every input checked as the best ones are (issue 36), end to end through the real binary:
 * an input never overwritten (the speed log); no pose that is none taken from any ground
 * truth; line files that are FIFOs, devices, not text
 * or of too long a line refused with file and line; nested YAML refused before libyaml parses
 * it. Each run is bounded in time, so what once hung fails here instead of holding the suite.
 */
#include <errno.h>
#include <fcntl.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>
#include <zlib.h>

#include "harness.h"
#include "mvod/calib.h"
#include "mvod/capture.h"

/* 10 frames of 320x240: enough for every refusal, which comes before the first frame. */
#define FRAMES 10
/*
 * Seconds a refused run may take: start-up is ~1 s; the cases here once took minutes (a
 * nested calibration 210 s) or for ever (a FIFO).
 */
#define BOUND_S 30

static char png[256], euroc[256], calib[300];

static int setup(void **state)
{
	(void)state;
	snprintf(png, sizeof(png), "%s", harness_tmp_path("png"));
	snprintf(euroc, sizeof(euroc), "%s", harness_tmp_path("euroc"));
	harness_synth(png, "forward", FRAMES, "png", "--size", "320x240", NULL);
	harness_synth(euroc, "forward", FRAMES, "euroc", "--size", "320x240", NULL);
	snprintf(calib, sizeof(calib), "%s/calib.json", png);
	return 0;
}

/*
 * Runs argv (NULL-terminated) for at most BOUND_S seconds, stdout and stderr into r; a run
 * that takes longer is killed and fails the test.
 */
static long max_rss_kb; /* of the last run_bounded */

static void run_bounded(char *const argv[], struct run_result *r)
{
	char out[300], err[300];
	snprintf(out, sizeof(out), "%s/run.out", harness_tmpdir());
	snprintf(err, sizeof(err), "%s/run.err", harness_tmpdir());
	pid_t pid = harness_spawn(argv, out, err);
	int st = 0, waited = 0;
	struct rusage ru;
	while (wait4(pid, &st, WNOHANG, &ru) == 0) {
		if (waited++ == BOUND_S * 20) {
			kill(pid, SIGKILL);
			waitpid(pid, &st, 0);
			fail_msg("%s still running after %d s", argv[0], BOUND_S);
		}
		usleep(50000);
	}
	max_rss_kb = ru.ru_maxrss;
	r->exited = WIFEXITED(st);
	r->status = WIFEXITED(st) ? WEXITSTATUS(st) : WTERMSIG(st);
	harness_read_file(out, r->out, sizeof(r->out));
	harness_read_file(err, r->err, sizeof(r->err));
}

/* The bytes of path, malloc'd, their count in *len. */
static char *slurp(const char *path, size_t *len)
{
	const char *slash = strrchr(path, '/');
	char dir[300];
	snprintf(dir, sizeof(dir), "%.*s", (int)(slash - path), path);
	return harness_slurp(dir, slash + 1, len);
}

/* mvod with the arguments (NULL-terminated) exits with code, in time, saying needle. */
static void expect_refused(int code, const char *needle, ...)
{
	char *argv[24] = {(char *)harness_bin("MVOD")};
	int n = 1;
	va_list ap;
	va_start(ap, needle);
	for (char *a; n < 23 && (a = va_arg(ap, char *));)
		argv[n++] = a;
	va_end(ap);
	struct run_result r;
	run_bounded(argv, &r);
	if (!r.exited || r.status != code || !strstr(r.err, needle))
		fail_msg("expected exit %d saying \"%s\", got %s %d: %s%s", code, needle,
			 r.exited ? "exit" : "signal", r.status, r.out, r.err);
}

/* bytes of c after prefix, into path. */
static void write_repeated(const char *path, const char *prefix, char c, size_t bytes)
{
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs(prefix, f);
	for (size_t i = 0; i < bytes; i++)
		fputc(c, f);
	fclose(f);
}

/* Writes text over path, keeping what was there in *saved (malloc'd) for put_back. */
static void replace(const char *path, const char *text, char **saved, size_t *len)
{
	*saved = slurp(path, len);
	harness_write_file(path, text);
}

static void put_back(const char *path, char *saved, size_t len)
{
	FILE *f = fopen(path, "wb");
	assert_non_null(f);
	assert_int_equal(fwrite(saved, 1, len, f), len);
	fclose(f);
	free(saved);
}

/* The lines of path with line k (from 1) replaced by line, in a static buffer. */
static const char *with_line(const char *path, int k, const char *line)
{
	static char text[65536];
	size_t len, n = 0;
	char *old = slurp(path, &len);
	int at = 1;
	for (char *s = old, *nl; s < old + len; s = nl + 1, at++) {
		nl = memchr(s, '\n', (size_t)(old + len - s));
		if (!nl)
			nl = old + len;
		n += (size_t)snprintf(text + n, sizeof(text) - n, "%.*s\n", at == k ? (int)strlen(line)
				      : (int)(nl - s), at == k ? line : s);
	}
	free(old);
	return text;
}

/* A folder of links to the clip's frames and a times.txt of text, or a FIFO when NULL. */
static const char *frames_with_times(const char *name, const char *text, size_t len)
{
	static char dir[300];
	char link[400], frame[400], times[400];
	snprintf(dir, sizeof(dir), "%s/%s", harness_tmpdir(), name);
	assert_int_equal(mkdir(dir, 0755), 0);
	for (int i = 0; i < FRAMES; i++) {
		snprintf(frame, sizeof(frame), "%s/images/%06d.png", png, i);
		snprintf(link, sizeof(link), "%s/%06d.png", dir, i);
		assert_int_equal(symlink(frame, link), 0);
	}
	snprintf(times, sizeof(times), "%s/times.txt", dir);
	if (!text) {
		assert_int_equal(mkfifo(times, 0600), 0);
		return dir;
	}
	FILE *f = fopen(times, "wb");
	assert_non_null(f);
	assert_int_equal(fwrite(text, 1, len, f), len);
	fclose(f);
	return dir;
}

/* A PNG chunk: length, type, data, CRC of type and data. */
static void put_chunk(FILE *f, const char *type, const uint8_t *data, uint32_t len)
{
	uint8_t be[4] = {len >> 24, len >> 16, len >> 8, len};
	fwrite(be, 1, 4, f);
	fwrite(type, 1, 4, f);
	data = data ? data : (const uint8_t *)""; /* crc32 of NULL is its initial value */
	fwrite(data, 1, len, f);
	uLong crc = crc32(crc32(0, (const Bytef *)type, 4), data, len);
	uint8_t c[4] = {crc >> 24, crc >> 16, crc >> 8, crc};
	fwrite(c, 1, 4, f);
}

/* An 8-bit grey PNG of w x h black pixels: a few hundred KB that decode to w * h bytes. */
static void write_png_bomb(const char *path, uint32_t w, uint32_t h)
{
	FILE *f = fopen(path, "wb");
	assert_non_null(f);
	fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
	uint8_t ihdr[13] = {w >> 24, w >> 16, w >> 8, w, h >> 24, h >> 16, h >> 8, h, 8, 0, 0, 0, 0};
	put_chunk(f, "IHDR", ihdr, 13);
	z_stream z = {0};
	assert_int_equal(deflateInit(&z, 9), Z_OK);
	uint8_t *row = calloc(1, w + 1), *out = malloc(1 << 20);
	assert_true(row && out);
	for (uint32_t y = 0; y <= h; y++) {
		z.next_in = row;
		z.avail_in = y < h ? w + 1 : 0;
		do {
			z.next_out = out;
			z.avail_out = 1 << 20;
			deflate(&z, y < h ? Z_NO_FLUSH : Z_FINISH);
			if (z.avail_out < 1 << 20)
				put_chunk(f, "IDAT", out, (1 << 20) - z.avail_out);
		} while (z.avail_out == 0 || (y == h && z.avail_in));
	}
	deflateEnd(&z);
	put_chunk(f, "IEND", NULL, 0);
	free(row);
	free(out);
	fclose(f);
}

/*
 * Class 1: the --speed-url log is an input, so the LCM log or the trajectory cannot be it
 * (both once wrote over it, exit 0: the speed gone from the frame where the writer caught up).
 */
static void test_speed_log_is_input(void **state)
{
	(void)state;
	char gt[300], log[300], speed[340], write[340], images[300];
	snprintf(gt, sizeof(gt), "%s/gt.tum", png);
	snprintf(log, sizeof(log), "%s/speed.lcmlog", harness_tmpdir());
	snprintf(images, sizeof(images), "images:%s/images", png);
	char *mk[] = {(char *)harness_bin("MVOD"), "speed-log", gt, log, NULL};
	struct run_result r;
	assert_int_equal(harness_run(mk, &r), 0);
	assert_int_equal(r.status, 0);
	size_t before_len, after_len;
	char *before = slurp(log, &before_len);
	snprintf(speed, sizeof(speed), "file://%s?mode=r", log);
	snprintf(write, sizeof(write), "file://%s?mode=w", log);
	expect_refused(2, "is a file this run reads", "--source", images, "--calib", calib, "--scale",
		       "external", "--speed-url", speed, "--lcm-url", write, NULL);
	expect_refused(2, "is a file this run reads", "--source", images, "--calib", calib, "--scale",
		       "external", "--speed-url", speed, "--no-lcm", "--trajectory", log, NULL);
	char *after = slurp(log, &after_len);
	assert_int_equal(after_len, before_len);
	assert_memory_equal(after, before, before_len);
	free(before);
	free(after);
}

/*
 * Class 2: ground truth that is no pose, from every source, is refused with file and line.
 * A zero quaternion in EuRoC's ground truth made 39 of 40 trajectory lines nan with --scale gt
 * (exit 0) and a "valid" mvod bench row; a KITTI rotation of zeros and a position of 1e308
 * were taken as they were.
 */
static void test_gt_poses(void **state)
{
	(void)state;
	char gt[300], source[300], out[300], csv[300], *saved;
	size_t len;
	snprintf(gt, sizeof(gt), "%s/mav0/state_groundtruth_estimate0/data.csv", euroc);
	snprintf(source, sizeof(source), "euroc:%s", euroc);
	snprintf(out, sizeof(out), "%s/gt-poses.tum", harness_tmpdir());
	snprintf(csv, sizeof(csv), "%s/gt-poses.csv", harness_tmpdir());
	replace(gt, with_line(gt, 3, "1403636579863555584,4.81,-1.72,0.77,0,0,0,0,0,0,0,0,0,0,0,0,"
			      "0"), &saved, &len);
	expect_refused(2, "data.csv line 3: quaternion (qx qy qz qw) = (0 0 0 0) has length 0, not 1",
		       "--source", source, "--scale", "gt", "--trajectory", out, "--no-lcm", NULL);
	expect_refused(2, "data.csv line 3: quaternion", "bench", "--source", source, "--scale", "gt",
		       "--csv", csv, NULL);
	assert_int_equal(access(out, F_OK), -1);
	assert_int_equal(access(csv, F_OK), -1);
	put_back(gt, saved, len);
	char kitti[300], tum[300], bad[300], images[300];
	snprintf(kitti, sizeof(kitti), "%s/gt.kitti", png);
	snprintf(tum, sizeof(tum), "%s/gt.tum", png);
	snprintf(bad, sizeof(bad), "%s/bad.kitti", harness_tmpdir());
	snprintf(images, sizeof(images), "images:%s/images", png);
	harness_write_file(bad, with_line(kitti, 2, "0 0 0 0.1 0 0 0 0 0 0 0 1"));
	expect_refused(2, "bad.kitti:2: rotation [0 0 0; 0 0 0; 0 0 0] is no rotation", "--source",
		       images, "--calib", calib, "--gt", bad, "--scale", "gt", "--no-lcm", NULL);
	snprintf(bad, sizeof(bad), "%s/bad.tum", harness_tmpdir());
	harness_write_file(bad, with_line(tum, 4, "0.300000 1e308 0 0.3 0 0 0 1"));
	expect_refused(2, "bad.tum:4: position (1e+308 0 0.3) m is that far", "--source", images,
		       "--calib", calib, "--gt", bad, "--no-lcm", NULL);
}

/*
 * Class 3: nested YAML is refused by the guard before libyaml parses it (a 300 KB calibration
 * took 210 s, a 1 MiB sensor.yaml over 13 minutes), with the line.
 */
static void test_nested_yaml(void **state)
{
	(void)state;
	char images[300], deep[300], sensor[300], source[300];
	snprintf(images, sizeof(images), "images:%s/images", png);
	snprintf(deep, sizeof(deep), "%s/deep.yaml", harness_tmpdir());
	write_repeated(deep, "%YAML:1.0\ncamera_matrix: ", '[', 300000);
	expect_refused(2, "deep.yaml: line 2: nested more than 64 levels deep", "--source", images,
		       "--calib", deep, "--no-lcm", NULL);
	snprintf(sensor, sizeof(sensor), "%s/mav0/cam0/sensor.yaml", euroc);
	write_repeated(sensor, "sensor_type: camera\nintrinsics: ", '[', (1 << 20) - 64);
	snprintf(source, sizeof(source), "euroc:%s", euroc);
	expect_refused(1, "sensor.yaml line 2: nested more than 64 levels deep", "--source", source,
		       "--no-lcm", NULL);
}

/*
 * Class 4: every line file through the one bounded reader. A FIFO (which blocked for ever), a
 * device (/dev/zero, read to 2 GB before "no poses"), a NUL (the line taken up to it, exit 0)
 * and a line too long are each refused with the file and the line.
 */
static void test_line_files(void **state)
{
	(void)state;
	char source[400];
	snprintf(source, sizeof(source), "images:%s", frames_with_times("fifo", NULL, 0));
	char fifo[420];
	snprintf(fifo, sizeof(fifo), "%s/times.txt", source + 7);
	int hold = open(fifo, O_RDWR | O_CLOEXEC); /* a writer that never writes */
	assert_true(hold >= 0);
	expect_refused(1, "times.txt is a FIFO: the times.txt must be a regular file", "--source",
		       source, "--calib", calib, "--no-lcm", NULL);
	close(hold);
	snprintf(source, sizeof(source), "images:%s/images", png);
	expect_refused(2, "ground truth: /dev/zero is a character device", "--source", source,
		       "--calib", calib, "--no-lcm", "--gt", "/dev/zero", NULL);
	static const char nul[] = "0.0\n0.1\n0.2\n0.3\n0.4\0 junk\n0.5\n0.6\n0.7\n0.8\n0.9\n";
	snprintf(source, sizeof(source), "images:%s", frames_with_times("nul", nul, sizeof(nul) - 1));
	expect_refused(1, "times.txt line 5: byte 0x00 at column 4 is no text", "--source", source,
		       "--calib", calib, "--no-lcm", NULL);
	static char text[10000];
	size_t n = (size_t)snprintf(text, sizeof(text), "0.0\n0.1\n0.2");
	memset(text + n, '0', 9000);
	memcpy(text + n + 9000, "\n0.3\n", 5);
	snprintf(source, sizeof(source), "images:%s", frames_with_times("long", text, n + 9005));
	expect_refused(1, "times.txt line 3 is longer than 8191 bytes", "--source", source, "--calib",
		       calib, "--no-lcm", NULL);
}

/*
 * Class 5: a later frame whose header states a size not the sequence's is skipped before it is
 * decoded. A 20000x20000 PNG bomb (~400 KB) decoded to 400 MB: mvod's peak RSS with it may
 * pass that of the same run with a plain frame in its place by 50 MB at most (the file is read
 * whole into the frame buffer; the rest is the run's own spread, under sanitizers too).
 */
static void test_png_bomb(void **state)
{
	(void)state;
	const char *dir = frames_with_times("bomb", "", 0);
	char frame[400], source[400];
	snprintf(frame, sizeof(frame), "%s/times.txt", dir);
	unlink(frame); /* no times: 10 Hz */
	snprintf(source, sizeof(source), "images:%s", dir);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", source, "--calib", calib,
			"--no-lcm", NULL};
	struct run_result r;
	run_bounded(argv, &r);
	assert_int_equal(r.status, 0);
	long plain_kb = max_rss_kb;
	snprintf(frame, sizeof(frame), "%s/000005.png", dir);
	unlink(frame);
	write_png_bomb(frame, 20000, 20000);
	run_bounded(argv, &r);
	if (!r.exited || r.status != 0 || !strstr(r.out, "1 skipped: 1 of another size"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
	if (max_rss_kb - plain_kb > 50 * 1024)
		fail_msg("mvod's RSS reached %ld MB, %ld MB with a plain frame: the bomb was decoded",
			 max_rss_kb / 1024, plain_kb / 1024);
}

/*
 * Class 5 and 8: a first image whose header states more pixels than any frame is refused by
 * its size, not "Input/output error" after a try to decode 4.3 gigapixels.
 */
static void test_huge_first_image(void **state)
{
	(void)state;
	char dir[300], frame[400], source[400];
	snprintf(dir, sizeof(dir), "%s/huge", harness_tmpdir());
	assert_int_equal(mkdir(dir, 0755), 0);
	snprintf(frame, sizeof(frame), "%s/000000.png", dir);
	FILE *f = fopen(frame, "wb");
	assert_non_null(f);
	fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
	static const uint8_t ihdr[13] = {0, 0, 0xFF, 0xFF, 0, 0, 0xFF, 0xFF, 8, 0, 0, 0, 0};
	put_chunk(f, "IHDR", ihdr, 13);
	put_chunk(f, "IEND", NULL, 0);
	fclose(f);
	snprintf(source, sizeof(source), "images:%s", dir);
	expect_refused(1, "000000.png is 65535x65535 pixels, its header says: more than the 67108864 "
		       "(8192x8192) of any frame mvod takes", "--source", source, "--calib", calib,
		       "--no-lcm", NULL);
	/* A video stream of 72 megapixels, refused by what its header says (no frame needed). */
	snprintf(dir, sizeof(dir), "%s/huge.avi", harness_tmpdir());
	char *mk[] = {(char *)harness_bin("MVOD_MKVIDEO"), dir, "rawvideo", "9000x8000", NULL};
	struct run_result r;
	assert_int_equal(harness_run(mk, &r), 0);
	assert_int_equal(r.status, 0);
	snprintf(source, sizeof(source), "file:%s", dir);
	expect_refused(1, "huge.avi: its frames are larger than the 67108864 pixels", "--source", source,
		       "--calib", calib, "--no-lcm", NULL);
}

/* Class 10: a video without a frame is refused at open, as an empty folder is (exit 0 before). */
static void test_video_without_frames(void **state)
{
	(void)state;
	char video[300], source[310], cal[300];
	snprintf(video, sizeof(video), "%s/empty.avi", harness_tmpdir());
	snprintf(source, sizeof(source), "file:%s", video);
	snprintf(cal, sizeof(cal), "%s/small.json", harness_tmpdir());
	harness_write_file(cal, "{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", "
			   "\"image_size\": [64, 48], \"K\": [[60, 0, 31.5], [0, 60, 23.5], [0, 0, "
			   "1]], \"distortion\": []}\n");
	char *mk[] = {(char *)harness_bin("MVOD_MKVIDEO"), video, "rawvideo", "64x48", NULL};
	struct run_result r;
	assert_int_equal(harness_run(mk, &r), 0);
	assert_int_equal(r.status, 0);
	expect_refused(1, "holds no frame", "--source", source, "--calib", cal, "--no-lcm", NULL);
}

/*
 * Class 6: --plot is an output checked at start like the others: no extension, one no encoder
 * takes, and /dev/null (no format either) were accepted and failed after the whole run.
 */
static void test_plot_checked_at_start(void **state)
{
	(void)state;
	char images[300], noext[300], xyz[300], gt[300];
	snprintf(images, sizeof(images), "images:%s/images", png);
	snprintf(gt, sizeof(gt), "%s/gt.tum", png);
	snprintf(noext, sizeof(noext), "%s/plot", harness_tmpdir());
	snprintf(xyz, sizeof(xyz), "%s/plot.xyz", harness_tmpdir());
	expect_refused(2, "--plot /dev/null: no extension names the image format", "--source",
		       images, "--calib", calib, "--no-lcm", "--plot", "/dev/null", NULL);
	expect_refused(2, "plot: no extension names the image format: name a FILE.png", "--source",
		       images, "--calib", calib, "--no-lcm", "--plot", noext, NULL);
	expect_refused(2, "plot.xyz: OpenCV writes no .xyz images", "--source", images, "--calib",
		       calib, "--no-lcm", "--plot", xyz, NULL);
	expect_refused(2, "plot.xyz: OpenCV writes no .xyz images", "bench", "--source", images,
		       "--calib", calib, "--gt", gt, "--plot", xyz, NULL);
	assert_int_equal(access(xyz, F_OK), -1);
	/* bench --plots: a folder, whose PNGs are no input; a file there failed after the run. */
	char plots[300], link[330];
	snprintf(plots, sizeof(plots), "%s/plots", harness_tmpdir());
	assert_int_equal(mkdir(plots, 0755), 0);
	snprintf(link, sizeof(link), "%s/errors.png", plots);
	assert_int_equal(symlink(gt, link), 0);
	expect_refused(2, "errors.png is a file this run reads", "bench", "--source", images,
		       "--calib", calib, "--gt", gt, "--plots", plots, NULL);
	expect_refused(2, "--plots ", "bench", "--source", images, "--calib", calib, "--gt", gt,
		       "--plots", gt, NULL);
	/* The run never began: no frame was processed. */
	struct run_result r;
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", images, "--calib", calib,
			"--no-lcm", "--plot", noext, NULL};
	run_bounded(argv, &r);
	assert_null(strstr(r.out, "frames in"));
}

/*
 * Class 9: what only an edit of the configuration fixes exits 2, which mvod.service does not
 * restart on (it restarted every 5 s on the 1 these gave); a run-time fault stays 1.
 */
static void test_configuration_exits_2(void **state)
{
	(void)state;
	char images[300];
	snprintf(images, sizeof(images), "images:%s/images", png);
	expect_refused(2, "--scale height needs the camera's height above the ground", "--source",
		       images, "--calib", calib, "--no-lcm", "--scale", "height", "--camera-height",
		       "0", NULL);
	expect_refused(2, "--scale external needs the robot's speed", "--source", images, "--calib",
		       calib, "--scale", "external", "--no-lcm", NULL);
	expect_refused(2, "unknown source scheme \"nosuch\"", "--source", "nosuch:x", "--no-lcm",
		       NULL);
	expect_refused(1, "cannot open image directory", "--source", "images:/nonexistent", "--calib", calib,
		       "--no-lcm", NULL);
}

/* Class 8: a reason after a path of 850 characters comes whole (512 bytes cut it off). */
static void test_long_path_reason(void **state)
{
	(void)state;
	char dir[1024], calib_path[1100], images[300];
	int n = snprintf(dir, sizeof(dir), "%s", harness_tmpdir());
	for (int i = 0; i < 4; i++) {
		n += snprintf(dir + n, sizeof(dir) - (size_t)n, "/%0200d", i);
		assert_int_equal(mkdir(dir, 0755), 0);
	}
	snprintf(calib_path, sizeof(calib_path), "%s/none.json", dir);
	snprintf(images, sizeof(images), "images:%s/images", png);
	expect_refused(2, "none.json: No such file or directory", "--source", images, "--calib",
		       calib_path, "--no-lcm", NULL);
}

/*
 * Class 8: a monoVO camera.txt with a negative principal point is in pixels; it was taken for
 * DSO's fractions of the image ("fx = 368640 px" of 576).
 */
static void test_mono_negative_principal_point(void **state)
{
	(void)state;
	const char *dir = harness_tmp_path("mono");
	char path[600], images[300], text[512] = "";
	assert_int_equal(mkdir(dir, 0755), 0);
	snprintf(images, sizeof(images), "%s/images", png);
	snprintf(path, sizeof(path), "%s/images", dir);
	assert_int_equal(symlink(images, path), 0);
	for (int i = 0; i < FRAMES; i++)
		snprintf(text + strlen(text), sizeof(text) - strlen(text), "%06d %.1f 10\n", i, i / 10.0);
	snprintf(path, sizeof(path), "%s/times.txt", dir);
	harness_write_file(path, text);
	snprintf(path, sizeof(path), "%s/camera.txt", dir);
	/* Both below 1, as fractions would be: cy = 120 alone kept the old rule from firing. */
	harness_write_file(path, "Pinhole 576 576 -5 -3 0\n320 240\ncrop\n320 240\n");
	snprintf(path, sizeof(path), "tum:%s", dir);
	struct mvod_source *src;
	char err[512];
	if (mvod_source_open(path, &src, err, sizeof(err)))
		fail_msg("%s", err);
	struct mvod_camera cam;
	assert_int_equal(mvod_source_camera(src, &cam), 0);
	assert_true(cam.fx == 576 && cam.fy == 576 && cam.cx == -5 && cam.cy == -3);
	mvod_source_close(src);
}

/*
 * Class 3: a stop is honoured while mvod starts. Blocked reading a --config FIFO that never
 * delivers (as in a libyaml parse of minutes), the first SIGTERM set a flag nobody read.
 */
static void test_stop_during_start_up(void **state)
{
	(void)state;
	char fifo[300], images[300];
	snprintf(fifo, sizeof(fifo), "%s/conf.fifo", harness_tmpdir());
	snprintf(images, sizeof(images), "images:%s/images", png);
	assert_int_equal(mkfifo(fifo, 0600), 0);
	int hold = open(fifo, O_RDWR | O_CLOEXEC); /* a writer that never writes */
	assert_true(hold >= 0);
	char *argv[] = {(char *)harness_bin("MVOD"), "-q", "--config", fifo, "--source", images,
			"--calib", calib, "--no-lcm", NULL};
	pid_t pid = harness_spawn(argv, NULL, NULL);
	harness_wait_open(pid, fifo);
	assert_int_equal(kill(pid, SIGTERM), 0);
	int st = 0;
	int waited = 0;
	while (waitpid(pid, &st, WNOHANG) == 0) {
		if (waited++ == BOUND_S * 20) {
			kill(pid, SIGKILL);
			waitpid(pid, &st, 0);
			fail_msg("SIGTERM during start-up not honoured in %d s", BOUND_S);
		}
		usleep(50000);
	}
	close(hold);
	assert_true(WIFSIGNALED(st) && WTERMSIG(st) == SIGTERM);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_speed_log_is_input),
		cmocka_unit_test(test_gt_poses),
		cmocka_unit_test(test_nested_yaml),
		cmocka_unit_test(test_line_files),
		cmocka_unit_test(test_png_bomb),
		cmocka_unit_test(test_huge_first_image),
		cmocka_unit_test(test_video_without_frames),
		cmocka_unit_test(test_plot_checked_at_start),
		cmocka_unit_test(test_configuration_exits_2),
		cmocka_unit_test(test_long_path_reason),
		cmocka_unit_test(test_mono_negative_principal_point),
		cmocka_unit_test(test_stop_during_start_up),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
