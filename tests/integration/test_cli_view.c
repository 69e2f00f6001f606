/*
 * mvod view end to end: the real mvod writes an LCM log of a synthetic clip, the real viewer
 * plays it back headless into a PNG; and the viewer's usage errors, bad URLs and SIGTERM.
 * The PNG is decoded here with zlib alone, independently of the OpenCV that wrote it.
 */
#include <errno.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>
#include <lcm/eventlog.h>
#include <zlib.h>

#include "harness.h"
#include "mvod/plot.h"
#include "mvod_pose_t.h"

#define FRAMES 30
#define EVERY 10
/* The viewer's picture: the plot and a 340 px panel of numbers to its right. */
#define VIEW_W (MVOD_PLOT_WIDTH + 340)
#define VIEW_H MVOD_PLOT_HEIGHT

static char dir[256];

static int setup(void **state)
{
	(void)state;
	snprintf(dir, sizeof(dir), "%s/seq", harness_tmpdir());
	harness_synth(dir, "forward", FRAMES, "mkv", NULL);
	return 0;
}

struct rgb_image {
	uint32_t w, h;
	unsigned char *px; /* w * h * 3, RGB */
};

static uint32_t be32(const unsigned char *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static int paeth(int a, int b, int c)
{
	int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
	return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

/* Undoes the PNG row filters in place (8-bit RGB: 3 bytes per pixel). */
static void unfilter(unsigned char *raw, struct rgb_image *img)
{
	size_t stride = (size_t)img->w * 3;
	for (uint32_t y = 0; y < img->h; y++) {
		const unsigned char *in = raw + y * (stride + 1);
		unsigned char *out = img->px + y * stride, *up = y ? out - stride : NULL;
		for (size_t i = 0; i < stride; i++) {
			int a = i >= 3 ? out[i - 3] : 0, b = up ? up[i] : 0,
			    c = up && i >= 3 ? up[i - 3] : 0;
			int pred[] = {0, a, b, (a + b) / 2, paeth(a, b, c)};
			assert_true(in[0] <= 4);
			out[i] = (unsigned char)(in[1 + i] + pred[in[0]]);
		}
	}
}

/* An 8-bit RGB, non-interlaced PNG (what OpenCV writes for a BGR image). */
static void read_png(const char *path, struct rgb_image *img)
{
	FILE *f = fopen(path, "rb");
	assert_non_null(f);
	unsigned char sig[8], hdr[8];
	assert_int_equal(fread(sig, 1, 8, f), 8);
	assert_memory_equal(sig, "\x89PNG\r\n\x1a\n", 8);
	unsigned char *idat = NULL;
	size_t idat_len = 0;
	while (fread(hdr, 1, 8, f) == 8) {
		uint32_t len = be32(hdr);
		unsigned char *chunk = malloc(len + 4);
		assert_non_null(chunk);
		assert_int_equal(fread(chunk, 1, len + 4, f), len + 4); /* data and CRC */
		if (!memcmp(hdr + 4, "IHDR", 4)) {
			img->w = be32(chunk);
			img->h = be32(chunk + 4);
			assert_int_equal(chunk[8], 8);  /* bit depth */
			assert_int_equal(chunk[9], 2);  /* RGB */
			assert_int_equal(chunk[12], 0); /* not interlaced */
		} else if (!memcmp(hdr + 4, "IDAT", 4)) {
			idat = realloc(idat, idat_len + len);
			assert_non_null(idat);
			memcpy(idat + idat_len, chunk, len);
			idat_len += len;
		}
		free(chunk);
	}
	fclose(f);
	uLongf raw_len = (uLongf)img->h * (img->w * 3 + 1);
	unsigned char *raw = malloc(raw_len);
	img->px = malloc((size_t)img->w * img->h * 3);
	assert_true(raw && img->px);
	assert_int_equal(uncompress(raw, &raw_len, idat, idat_len), Z_OK);
	assert_int_equal(raw_len, (uLongf)img->h * (img->w * 3 + 1));
	unfilter(raw, img);
	free(raw);
	free(idat);
}

static long count_color(const struct rgb_image *img, int r, int g, int b)
{
	long n = 0;
	for (size_t i = 0; i < (size_t)img->w * img->h; i++)
		n += img->px[3 * i] == r && img->px[3 * i + 1] == g && img->px[3 * i + 2] == b;
	return n;
}

struct summary {
	long long poses, statuses;
	char state[32];
	int writes;
};

static void parse_summary(const char *out, struct summary *s)
{
	const char *line = strstr(out, "mvod view: ");
	if (!line)
		fail_msg("no summary in: %s", out);
	if (sscanf(line, "mvod view: %lld poses, %lld status messages, last state %31[A-Z_]", &s->poses,
		   &s->statuses, s->state) != 3)
		fail_msg("bad summary: %s", line);
	const char *w = strstr(line, " written ");
	s->writes = w ? atoi(w + 9) : -1;
}

static void run_view(char **extra, int nextra, struct run_result *r)
{
	char *argv[16] = {(char *)harness_bin("MVOD"), "view"};
	assert_true(nextra <= 13);
	for (int i = 0; i < nextra; i++)
		argv[2 + i] = extra[i];
	argv[2 + nextra] = NULL;
	assert_int_equal(harness_run(argv, r), 0);
	assert_true(r->exited);
}

/* mvod processes the clip into a log; returns the frame count its summary reports. */
static long long record_log(const char *log)
{
	char video[300], calib[300], url[400];
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(url, sizeof(url), "file://%s?mode=w", log);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib,
			"--lcm-url", url, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mvod failed: %s", r.err);
	long long frames = -1;
	const char *s = strstr(r.out, "mvod: ");
	assert_non_null(s);
	assert_int_equal(sscanf(s, "mvod: %lld frames", &frames), 1);
	return frames;
}

static void test_log_to_png(void **state)
{
	(void)state;
	char log[300], url[400], png[300];
	snprintf(log, sizeof(log), "%s/run.lcmlog", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s?mode=r&speed=0", log);
	snprintf(png, sizeof(png), "%s/view.png", harness_tmpdir());
	long long frames = record_log(log);
	assert_int_equal(frames, FRAMES);

	char *args[] = {"--lcm-url", url, "--png", png, "--every", "10"};
	struct run_result r;
	run_view(args, 6, &r);
	if (r.status)
		fail_msg("mvod view failed (%d): %s", r.status, r.err);
	struct summary s;
	parse_summary(r.out, &s);
	assert_int_equal(s.poses, frames);
	/* mvod sends status once a second and when it stops: at least the last one. */
	assert_true(s.statuses >= 1);
	/* The last message of the log is mvod's status as it stops. */
	assert_string_equal(s.state, "STOPPING");
	/* After poses 10, 20 and 30, and once more at the end of the log. */
	assert_int_equal(s.writes, FRAMES / EVERY + 1);
	assert_non_null(strstr(r.out, "(end of log)"));

	struct rgb_image img;
	read_png(png, &img);
	assert_int_equal(img.w, VIEW_W);
	assert_int_equal(img.h, VIEW_H);
	/*
	 * The estimate's colour (BGR 190,90,20 in plot_shim.cpp) at full strength along the
	 * anti-aliased 2 px line: the path across the plot's height gave 1261 such pixels, the
	 * legend's 28 px sample line alone gives under 60, so 500 tells a drawn path from none.
	 * The heading arrow's red, in the plot and on the compass, gave 509; 100 leaves room
	 * for anti-aliasing differences and still needs a drawn arrow.
	 */
	long path_px = count_color(&img, 20, 90, 190), arrow_px = count_color(&img, 210, 30, 30);
	printf("path pixels %ld, heading pixels %ld\n", path_px, arrow_px);
	assert_true(path_px > 500);
	assert_true(arrow_px > 100);
	free(img.px);
}

/* A log written here: poses at known places, the last one far behind in the log's clock. */
static void write_slow_log(const char *path)
{
	lcm_eventlog_t *ev = lcm_eventlog_create(path, "w");
	assert_non_null(ev);
	static const int64_t t_us[] = {0, 100000, 600000000};
	for (int i = 0; i < 3; i++) {
		mvod_pose_t msg = {.utime = t_us[i], .frame = i, .position = {0, 0, i},
				   .orientation = {1, 0, 0, 0}, .state = MVOD_POSE_T_STATE_TRACKING};
		unsigned char buf[256];
		int len = mvod_pose_t_encode(buf, 0, sizeof(buf), &msg);
		assert_true(len > 0);
		lcm_eventlog_event_t e = {.timestamp = t_us[i], .channellen = 9, .datalen = len,
					  .channel = "MVOD_POSE", .data = buf};
		assert_int_equal(lcm_eventlog_write_event(ev, &e), 0);
	}
	lcm_eventlog_destroy(ev);
}

/* SIGTERM while the viewer waits on a real-time playback: one last PNG, exit 0. */
static void test_sigterm_writes_png(void **state)
{
	(void)state;
	char log[300], url[400], png[300];
	snprintf(log, sizeof(log), "%s/slow.lcmlog", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s?mode=r", log);
	snprintf(png, sizeof(png), "%s/slow.png", harness_tmpdir());
	write_slow_log(log);
	pid_t pid = fork();
	assert_true(pid >= 0);
	if (pid == 0) {
		freopen("/dev/null", "w", stdout);
		execl(harness_bin("MVOD"), "mvod", "view", "--lcm-url", url, "--png", png, "--every",
		      "1", (char *)NULL);
		_exit(127);
	}
	/* The first pose's PNG shows the handler is in place; the third is ten minutes away. */
	struct stat st;
	for (int i = 0; i < 6000 && stat(png, &st) != 0; i++)
		usleep(10000);
	assert_int_equal(stat(png, &st), 0);
	kill(pid, SIGTERM);
	int status;
	assert_int_equal(waitpid(pid, &status, 0), pid);
	assert_true(WIFEXITED(status));
	assert_int_equal(WEXITSTATUS(status), 0);
	struct rgb_image img;
	read_png(png, &img);
	assert_int_equal(img.w, VIEW_W);
	free(img.px);
}

static void test_no_display_is_usage_error(void **state)
{
	(void)state;
	char *saved_x = getenv("DISPLAY"), *saved_w = getenv("WAYLAND_DISPLAY");
	char *x = saved_x ? strdup(saved_x) : NULL, *w = saved_w ? strdup(saved_w) : NULL;
	unsetenv("DISPLAY");
	unsetenv("WAYLAND_DISPLAY");
	struct run_result r;
	run_view(NULL, 0, &r);
	assert_int_equal(r.status, 2);
	assert_non_null(strstr(r.err, "no display"));
	assert_non_null(strstr(r.err, "--png"));
	if (x)
		setenv("DISPLAY", x, 1);
	if (w)
		setenv("WAYLAND_DISPLAY", w, 1);
	free(x);
	free(w);
}

static void test_bad_url_fails(void **state)
{
	(void)state;
	char png[300];
	snprintf(png, sizeof(png), "%s/never.png", harness_tmpdir());
	static const char *const urls[] = {"bogus://x", "file:///nonexistent/run.lcmlog?mode=r"};
	for (int i = 0; i < 2; i++) {
		char *args[] = {"--lcm-url", (char *)urls[i], "--png", png};
		struct run_result r;
		run_view(args, 4, &r);
		assert_int_equal(r.status, 1);
		/* A missing log is named as such before LCM is asked (test_view_log.c). */
		assert_non_null(strstr(r.err, i == 0 ? "cannot open LCM at bogus://x"
						     : "cannot read /nonexistent/run.lcmlog"));
		assert_int_equal(access(png, F_OK), -1);
	}
}

static void test_usage_errors(void **state)
{
	(void)state;
	char png[300], url[400];
	snprintf(png, sizeof(png), "%s/never.png", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s/run.lcmlog?mode=w", harness_tmpdir());
	char *unknown[] = {"--png", png, "--frobnicate"};
	char *every_alone[] = {"--every", "5"};
	char *bad_every[] = {"--png", png, "--every", "0"};
	/* Opening the log to write would truncate what it should show. */
	char *writes_log[] = {"--lcm-url", url, "--png", png};
	struct {
		char **args;
		int n;
		const char *msg;
	} cases[] = {{unknown, 3, "unknown or incomplete option '--frobnicate'"},
		     {every_alone, 2, "--every needs --png"},
		     {bad_every, 4, "--every 0: expected an integer"},
		     {writes_log, 4, "only reads logs"}};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		struct run_result r;
		run_view(cases[i].args, cases[i].n, &r);
		assert_int_equal(r.status, 2);
		if (!strstr(r.err, cases[i].msg))
			fail_msg("expected '%s' in: %s", cases[i].msg, r.err);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_log_to_png),
		cmocka_unit_test(test_sigterm_writes_png),
		cmocka_unit_test(test_no_display_is_usage_error),
		cmocka_unit_test(test_bad_url_fails),
		cmocka_unit_test(test_usage_errors),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
