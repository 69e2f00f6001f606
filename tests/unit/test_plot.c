/* The top-down plot and the charts: real PNGs of the designed size, written atomically. */
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "mvod/plot.h"

/* The canvas size plot_shim.cpp draws on. */
#define PLOT_W 1000
#define PLOT_H 800
#define N_CIRCLE 200

struct tmpdir {
	char dir[64];
};

static int setup(void **state)
{
	struct tmpdir *t = malloc(sizeof(*t));
	if (!t)
		return -1;
	strcpy(t->dir, "/tmp/mvod-test-plot-XXXXXX");
	if (!mkdtemp(t->dir)) {
		free(t);
		return -1;
	}
	*state = t;
	return 0;
}

/* Leaves the PNGs for a human to look at when MVOD_KEEP_PLOTS is set. */
static int teardown(void **state)
{
	struct tmpdir *t = *state;
	if (!getenv("MVOD_KEEP_PLOTS")) {
		DIR *d = opendir(t->dir);
		struct dirent *e;
		while (d && (e = readdir(d)) != NULL) {
			char p[sizeof(t->dir) + sizeof(e->d_name) + 1];
			if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
				continue;
			snprintf(p, sizeof(p), "%s/%s", t->dir, e->d_name);
			unlink(p);
		}
		if (d)
			closedir(d);
		rmdir(t->dir);
	}
	free(t);
	return 0;
}

static uint32_t be32(const unsigned char *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* Signature, then IHDR first with the canvas size. */
static void assert_png(const char *path, uint32_t w, uint32_t h)
{
	static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	unsigned char head[24];
	FILE *f = fopen(path, "rb");
	assert_non_null(f);
	assert_int_equal(fread(head, 1, sizeof(head), f), sizeof(head));
	fclose(f);
	assert_memory_equal(head, sig, sizeof(sig));
	assert_memory_equal(head + 12, "IHDR", 4);
	assert_int_equal(be32(head + 16), w);
	assert_int_equal(be32(head + 20), h);
}

/* Entries other than "." and ".." whose name starts with a dot: temporaries. */
static int count_hidden(const char *dir)
{
	DIR *d = opendir(dir);
	assert_non_null(d);
	int n = 0;
	struct dirent *e;
	while ((e = readdir(d)) != NULL)
		if (e->d_name[0] == '.' && strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
			n++;
	closedir(d);
	return n;
}

static void join(char *out, size_t n, const char *dir, const char *name)
{
	snprintf(out, n, "%s/%s", dir, name);
}

static void circle(double *xyz, int n, double r)
{
	for (int i = 0; i < n; i++) {
		double a = 2 * M_PI * i / (n - 1);
		xyz[3 * i] = r * sin(a);
		xyz[3 * i + 1] = 0.0;
		xyz[3 * i + 2] = r - r * cos(a);
	}
}

/* Camera-to-world rotation about y by a: forward (0,0,1) turns to (sin a, 0, cos a). */
static void yaw(double a, double R[9])
{
	const double M[9] = {cos(a), 0, sin(a), 0, 1, 0, -sin(a), 0, cos(a)};
	memcpy(R, M, sizeof(M));
}

static void test_circle_vs_gt(void **state)
{
	struct tmpdir *t = *state;
	double est[3 * N_CIRCLE], gt[3 * N_CIRCLE], R[9];
	char path[128];
	circle(est, N_CIRCLE, 5.0);
	circle(gt, N_CIRCLE, 5.4);
	yaw(0.0, R);
	join(path, sizeof(path), t->dir, "circle.png");

	assert_int_equal(mvod_plot_topdown(path, "circle: estimate vs ground truth", est,
					   N_CIRCLE, R, gt, N_CIRCLE, "m"), 0);
	assert_png(path, PLOT_W, PLOT_H);
	assert_int_equal(count_hidden(t->dir), 0);
}

/* The x or y (axis 0 or 1) of every pixel of exactly colour bgr, in order; how many. */
static int colour_coords(const struct mvod_image *im, const uint8_t bgr[3], int axis, int *out)
{
	int n = 0;
	for (int y = 0; y < im->h; y++)
		for (int x = 0; x < im->w; x++)
			if (!memcmp(im->data + (size_t)y * im->stride + 3 * x, bgr, 3))
				out[n++] = axis ? y : x;
	return n;
}

static int cmp_int(const void *a, const void *b)
{
	return *(const int *)a - *(const int *)b;
}

/*
 * Width of the middle 90 % of the pixels of colour bgr along an axis: for a ring drawn evenly
 * around, 2 R cos(9 deg) whichever the axis. Percentiles, not the extremes, so that the
 * legend's short sample of the same colour does not count.
 */
static double spread(const struct mvod_image *im, const uint8_t bgr[3], int axis, int *n)
{
	static int c[PLOT_W * PLOT_H];
	*n = colour_coords(im, bgr, axis, c);
	if (*n < 20)
		return 0;
	qsort(c, (size_t)*n, sizeof(c[0]), cmp_int);
	return c[*n * 95 / 100] - c[*n * 5 / 100];
}

/*
 * The pixels, not only the PNG header: the estimate (radius 5 m, blue) and the ground truth
 * (radius 5.4 m, grey, dashed) come out as rings of those radii, at one scale for both axes
 * (measured 523 x 525 px), on a white canvas.
 */
static void test_circle_pixels(void **state)
{
	(void)state;
	static uint8_t px[PLOT_W * PLOT_H * 3];
	struct mvod_image im = {PLOT_W, PLOT_H, 3 * PLOT_W, MVOD_PIX_BGR, px};
	double est[3 * N_CIRCLE], gt[3 * N_CIRCLE];
	circle(est, N_CIRCLE, 5.0);
	circle(gt, N_CIRCLE, 5.4);
	assert_int_equal(mvod_plot_topdown_draw(&im, "rings", est, N_CIRCLE, NULL, gt, N_CIRCLE, "m"),
			 0);
	static const uint8_t white[3] = {255, 255, 255};
	assert_memory_equal(px, white, 3);
	assert_memory_equal(px + sizeof(px) - 3, white, 3);
	/* plot_shim.cpp's EST_COLOR and GT_COLOR, as B, G, R. */
	static const uint8_t blue[3] = {190, 90, 20}, grey[3] = {70, 70, 70};
	int ne, ng;
	double ex = spread(&im, blue, 0, &ne), ey = spread(&im, blue, 1, &ne);
	double gx = spread(&im, grey, 0, &ng);
	print_message("estimate: %d px, %.0f x %.0f; ground truth: %d px, %.0f across\n", ne, ex,
		      ey, ng, gx);
	/* A 2 px line around a ring several hundred pixels across: thousands of pixels. */
	assert_true(ne > 1000 && ng > 500);
	/* Equal aspect: as wide as tall, to the 3 % the legend sample and line ends may shift. */
	assert_true(fabs(ex / ey - 1) < 0.03);
	/*
	 * 5.4 / 5 = 1.08 between the rings across (measured 1.082). Not down: the legend's dashed
	 * sample and the grey end marker, both in the ground truth's colour, sit above and below.
	 */
	assert_true(fabs(gx / ex - 1.08) < 0.02);
}

/* Also replaces an existing file by rename. */
static void test_static_point(void **state)
{
	struct tmpdir *t = *state;
	const double est[3] = {2.0, 0.0, -1.0};
	char path[128];
	join(path, sizeof(path), t->dir, "static.png");
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs("old", f);
	fclose(f);

	assert_int_equal(mvod_plot_topdown(path, "static camera", est, 1, NULL, NULL, 0, "m"), 0);
	assert_png(path, PLOT_W, PLOT_H);
	assert_int_equal(count_hidden(t->dir), 0);
}

static void test_degenerate_inputs(void **state)
{
	struct tmpdir *t = *state;
	double est[3 * 5];
	char path[128];
	for (int i = 0; i < 5; i++) {
		est[3 * i] = i;
		est[3 * i + 1] = 0;
		est[3 * i + 2] = 2.0 * i;
	}
	est[3 * 2] = NAN;
	join(path, sizeof(path), t->dir, "nan.png");
	assert_int_equal(mvod_plot_topdown(path, "with a NaN", est, 5, NULL, NULL, 0, "m"), 0);
	assert_png(path, PLOT_W, PLOT_H);

	/* Diverged values must neither hang the tick loops nor overflow the view. */
	const double wild[9] = {-DBL_MAX, 0, DBL_MAX, INFINITY, 0, 1e300, 1.0, 0.0, 1.0};
	const double R_nan[9] = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
	join(path, sizeof(path), t->dir, "wild.png");
	assert_int_equal(mvod_plot_topdown(path, "diverged", wild, 3, R_nan, wild, 3, "m"), 0);
	assert_png(path, PLOT_W, PLOT_H);

	join(path, sizeof(path), t->dir, "empty.png");
	assert_int_equal(mvod_plot_topdown(path, NULL, NULL, 0, NULL, NULL, 0, "m"), 0);
	assert_png(path, PLOT_W, PLOT_H);
	assert_int_equal(count_hidden(t->dir), 0);
}

/* A straight drive forward and a long zig-zag (the shape a lawn-mower pattern makes). */
static void test_line_and_zigzag(void **state)
{
	struct tmpdir *t = *state;
	enum { N = 2000 };
	static double est[3 * N], gt[3 * N];
	double R[9];
	char path[128];
	for (int i = 0; i < N; i++) {
		gt[3 * i] = 0.0;
		gt[3 * i + 1] = 0.0;
		gt[3 * i + 2] = 0.05 * i;
		est[3 * i] = 0.002 * i * sin(i * 0.01);
		est[3 * i + 1] = 0.0;
		est[3 * i + 2] = 0.048 * i;
	}
	yaw(0.1, R);
	join(path, sizeof(path), t->dir, "line.png");
	assert_int_equal(mvod_plot_topdown(path, "straight line", est, N, R, gt, N, "m"), 0);
	assert_png(path, PLOT_W, PLOT_H);

	for (int i = 0; i < N; i++) {
		double leg = fmod(i / 100.0, 2.0);
		gt[3 * i] = (leg < 1 ? leg : 2 - leg) * 30.0;
		gt[3 * i + 2] = i * 0.1;
		est[3 * i] = gt[3 * i] * 1.03 + 0.0004 * i;
		est[3 * i + 2] = gt[3 * i + 2] * 0.98;
	}
	yaw(-2.0, R);
	join(path, sizeof(path), t->dir, "zigzag.png");
	assert_int_equal(mvod_plot_topdown(path, "zig-zag, 2000 poses", est, N, R, gt, N, "m"), 0);
	assert_png(path, PLOT_W, PLOT_H);
	assert_int_equal(count_hidden(t->dir), 0);
}

static void test_bad_args(void **state)
{
	struct tmpdir *t = *state;
	const double est[3] = {0};
	char path[128];
	join(path, sizeof(path), t->dir, "x.png");
	assert_int_equal(mvod_plot_topdown(path, "t", est, -1, NULL, NULL, 0, "m"), -EINVAL);
	assert_int_equal(mvod_plot_topdown(path, "t", NULL, 3, NULL, NULL, 0, "m"), -EINVAL);
	assert_int_equal(mvod_plot_topdown(path, "t", est, 1, NULL, NULL, -2, "m"), -EINVAL);
	assert_int_equal(mvod_plot_topdown(NULL, "t", est, 1, NULL, NULL, 0, "m"), -EINVAL);
	assert_int_equal(mvod_plot_topdown(path, "t", est, 1, NULL, NULL, 0, NULL), -EINVAL);
	join(path, sizeof(path), t->dir, "noext");
	assert_int_equal(mvod_plot_topdown(path, "t", est, 1, NULL, NULL, 0, "m"), -EINVAL);
	join(path, sizeof(path), t->dir, "x.nosuchformat");
	assert_int_equal(mvod_plot_topdown(path, "t", est, 1, NULL, NULL, 0, "m"), -EINVAL);
	assert_int_equal(count_hidden(t->dir), 0);
	assert_int_equal(access(path, F_OK), -1);
}

static void test_unwritable(void **state)
{
	struct tmpdir *t = *state;
	const double est[6] = {0, 0, 0, 1, 0, 1};
	char path[128];
	assert_true(mvod_plot_topdown("/nonexistent/dir/x.png", "t", est, 2, NULL, NULL, 0, "m") < 0);
	assert_int_equal(access("/nonexistent/dir/x.png", F_OK), -1);

	/* A directory where the file should go: the temp is written, rename fails, temp removed. */
	join(path, sizeof(path), t->dir, "taken.png");
	assert_int_equal(mkdir(path, 0700), 0);
	assert_true(mvod_plot_topdown(path, "t", est, 2, NULL, NULL, 0, "m") < 0);
	assert_int_equal(count_hidden(t->dir), 0);
	rmdir(path);
}

/* A chart is 60 px of title, then per panel its plot area, 70 px of x axis and a 10 px gap. */
static uint32_t chart_height(int panels)
{
	int plot_h = panels == 1 ? 640 : (780 / panels > 200 ? 780 / panels : 200);
	return (uint32_t)(60 + panels * (plot_h + 70 + 10));
}

static void test_chart_panels(void **state)
{
	struct tmpdir *t = *state;
	double x[50], y[50], y2[50];
	for (int i = 0; i < 50; i++) {
		x[i] = i;
		y[i] = sin(0.2 * i);
		y2[i] = 0.01 * i * i;
	}
	/* Gaps are left out, not drawn to the origin. */
	y[10] = NAN;
	y2[20] = INFINITY;
	char path[128];
	join(path, sizeof(path), t->dir, "chart1.png");
	struct mvod_plot_series two[2] = {
		{"sin", x, y, 50, MVOD_PLOT_LINE, NULL},
		{"square", x, y2, 50, MVOD_PLOT_DASHED, NULL},
	};
	struct mvod_plot_panel one = {"frame", "value [m]", two, 2, false};
	assert_int_equal(mvod_plot_chart(path, "one panel", &one, 1), 0);
	assert_png(path, PLOT_W, chart_height(1));
	struct mvod_plot_panel three[3] = {
		{"frame", "a", &two[0], 1, false},
		{"frame", "b", &two[1], 1, false},
		{"frame", "empty", NULL, 0, false}};
	join(path, sizeof(path), t->dir, "chart3.png");
	assert_int_equal(mvod_plot_chart(path, "three panels", three, 3), 0);
	assert_png(path, PLOT_W, chart_height(3));
	assert_int_equal(count_hidden(t->dir), 0);
}

static void test_chart_labelled_points(void **state)
{
	struct tmpdir *t = *state;
	const double x[3] = {12, 40, 130}, y[3] = {0.2, 0.15, 0.09};
	const char *const labels[3] = {"orb bf-cross 1000", "orb bf 2000", "sift flann-ratio 3000"};
	struct mvod_plot_series s = {"configuration", x, y, 3, MVOD_PLOT_POINTS, labels};
	struct mvod_plot_panel p = {"median frame time [ms], log scale", "err_avg", &s, 1, true};
	char path[128];
	join(path, sizeof(path), t->dir, "points.png");
	assert_int_equal(mvod_plot_chart(path, "error against speed", &p, 1), 0);
	assert_png(path, PLOT_W, chart_height(1));
	/* Bad arguments write nothing. */
	struct mvod_plot_series bad = {"x", NULL, y, 3, MVOD_PLOT_LINE, NULL};
	struct mvod_plot_panel bp = {"x", "y", &bad, 1, false};
	join(path, sizeof(path), t->dir, "bad.png");
	assert_int_equal(mvod_plot_chart(path, "t", &bp, 1), -EINVAL);
	assert_int_equal(mvod_plot_chart(path, "t", &p, 0), -EINVAL);
	assert_int_equal(mvod_plot_chart(NULL, "t", &p, 1), -EINVAL);
	join(path, sizeof(path), t->dir, "noext");
	assert_int_equal(mvod_plot_chart(path, "t", &p, 1), -EINVAL);
	assert_int_equal(access(path, F_OK), -1);
	assert_int_equal(count_hidden(t->dir), 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test_setup_teardown(test_circle_vs_gt, setup, teardown),
		cmocka_unit_test(test_circle_pixels),
		cmocka_unit_test_setup_teardown(test_static_point, setup, teardown),
		cmocka_unit_test_setup_teardown(test_degenerate_inputs, setup, teardown),
		cmocka_unit_test_setup_teardown(test_line_and_zigzag, setup, teardown),
		cmocka_unit_test_setup_teardown(test_bad_args, setup, teardown),
		cmocka_unit_test_setup_teardown(test_unwritable, setup, teardown),
		cmocka_unit_test_setup_teardown(test_chart_panels, setup, teardown),
		cmocka_unit_test_setup_teardown(test_chart_labelled_points, setup, teardown),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
