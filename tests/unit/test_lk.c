/*
 * The Lucas-Kanade tracker of vo/lk.h on pyramids built here (OpenCV's layout: bordered levels,
 * Scharr derivatives as (d/dx, d/dy) pairs): every vector path this build and machine have
 * (SSE2 and AVX2 on x86-64, NEON on arm64) gives exactly what the plain C gives; a smooth
 * texture moved by a known sub-pixel shift is tracked to it; a flat patch and a window that
 * leaves the image fail; the Scharr derivatives equal the kernels' on every path. Needs only the C
 * library and cmocka, so make cross-arm64 runs it under qemu too; where meson builds it, with
 * OpenCV's calcOpticalFlowPyrLK beside it (lk_opencv.cpp), every status equals OpenCV's on
 * low-contrast, edge and corner patches, and every position where both accept.
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "vo/frontend/lk.h"
#ifdef MVOD_HAVE_OPENCV_LK
#include "lk_opencv.h"
#include "mvod/image.h"
#include "vo/frontend/klt_shim.h"
#endif

enum { W = 160, H = 120, BORDER = 32, LEVELS = 2 };

/* One level: pixels and derivatives over the level and its border. */
struct level {
	uint8_t img[(H + 2 * BORDER) * (W + 2 * BORDER)];
	int16_t deriv[2 * (H + 2 * BORDER) * (W + 2 * BORDER)];
	int w, h;
};

static struct level I_[LEVELS + 1], J_[LEVELS + 1];
static struct mvod_lk_level I[LEVELS + 1], J[LEVELS + 1];

static uint64_t next_word(uint64_t *s)
{
	*s ^= *s << 13;
	*s ^= *s >> 7;
	*s ^= *s << 17;
	return *s;
}

/* Scharr derivatives of every pixel but the outermost ring (zero there), as OpenCV scales them. */
static void scharr(struct level *L, struct mvod_lk_level *out)
{
	int sw = L->w + 2 * BORDER, sh = L->h + 2 * BORDER;
	memset(L->deriv, 0, sizeof(L->deriv));
	for (int y = 1; y < sh - 1; y++)
		for (int x = 1; x < sw - 1; x++) {
			const uint8_t *p = L->img + y * sw + x;
			int dx = 3 * (p[-sw + 1] - p[-sw - 1]) + 10 * (p[1] - p[-1]) +
				 3 * (p[sw + 1] - p[sw - 1]);
			int dy = 3 * (p[sw - 1] - p[-sw - 1]) + 10 * (p[sw] - p[-sw]) +
				 3 * (p[sw + 1] - p[-sw + 1]);
			L->deriv[2 * (y * sw + x)] = (int16_t)dx;
			L->deriv[2 * (y * sw + x) + 1] = (int16_t)dy;
		}
	*out = (struct mvod_lk_level){.img = L->img + BORDER * sw + BORDER,
				      .deriv = L->deriv + 2 * (BORDER * sw + BORDER),
				      .stride = sw,
				      .dstride = 2 * sw,
				      .w = L->w,
				      .h = L->h,
				      .border = BORDER};
}

/*
 * A smooth texture at level-0 position (x, y): three waves of 24-61 pixels (3-7.6 at level 2,
 * above its Nyquist limit of 2), grey levels 28-228.
 */
static double texture(double x, double y)
{
	return 128 + 40 * sin(x / 7.0 + 0.3) * cos(y / 9.7) + 35 * sin((x + 2 * y) / 5.3) +
	       25 * cos((3 * x - y) / 4.1 + 1.0);
}

/* Level l of the texture moved by (dx, dy) level-0 pixels: pixel (x, y) samples (x 2^l, y 2^l). */
static void render(struct level *L, struct mvod_lk_level *out, int l, double dx, double dy)
{
	L->w = W >> l;
	L->h = H >> l;
	int sw = L->w + 2 * BORDER, sh = L->h + 2 * BORDER;
	for (int y = 0; y < sh; y++)
		for (int x = 0; x < sw; x++) {
			double v = texture((x - BORDER) * (double)(1 << l) - dx,
					   (y - BORDER) * (double)(1 << l) - dy);
			L->img[y * sw + x] = (uint8_t)lrint(v);
		}
	scharr(L, out);
}

static void render_pair(double dx, double dy)
{
	for (int l = 0; l <= LEVELS; l++) {
		render(&I_[l], &I[l], l, 0, 0);
		render(&J_[l], &J[l], l, dx, dy);
	}
}

enum { N = 200 };

/* Which paths compare_paths ran (bit path): the log says which this machine tested. */
static int paths_compared;

/* Every path this build and machine have on the same points: equal to the plain C bit for bit. */
static void compare_paths(const struct mvod_lk_params *p, const float *from, const float *guess)
{
	float a[2 * N], b[2 * N];
	uint8_t oka[N], okb[N];
	memcpy(b, guess, sizeof(b));
	assert_int_equal(mvod_lk_flow_on(MVOD_LK_PLAIN, I, J, p, from, b, N, okb), 0);
	for (int path = MVOD_LK_VECTOR; path <= MVOD_LK_AVX2; path++) {
		memcpy(a, guess, sizeof(a));
		if (mvod_lk_flow_on((enum mvod_lk_path)path, I, J, p, from, a, N, oka) == -ENOTSUP)
			continue;
		for (int i = 0; i < N; i++)
			if (memcmp(&a[2 * i], &b[2 * i], 2 * sizeof(float)) || oka[i] != okb[i])
				fail_msg("path %d, win %d, point %d: (%.9g, %.9g) %d, plain (%.9g, "
					 "%.9g) %d",
					 path, p->win, i, a[2 * i], a[2 * i + 1], oka[i], b[2 * i],
					 b[2 * i + 1], okb[i]);
		paths_compared |= 1 << path;
	}
}

/* Random points inside the image, guesses up to 6 pixels from them. */
static void random_points(uint64_t *seed, float *from, float *guess)
{
	for (int i = 0; i < N; i++) {
		from[2 * i] = 4 + (float)(next_word(seed) % 15000) / 100.0f;
		from[2 * i + 1] = 4 + (float)(next_word(seed) % 11000) / 100.0f;
		guess[2 * i] = from[2 * i] + (float)((int)(next_word(seed) % 1200) - 600) / 100.0f;
		guess[2 * i + 1] =
		    from[2 * i + 1] + (float)((int)(next_word(seed) % 1200) - 600) / 100.0f;
	}
}

static void test_vector_equals_plain(void **state)
{
	(void)state;
	static const int wins[] = {3, 8, 9, 15, 21, 24, MVOD_LK_MAX_WIN};
	uint64_t seed = 0x9e3779b97f4a7c15u;
	float from[2 * N], guess[2 * N];
	for (int k = 0; k < 3; k++) {
		/*
		 * Random bytes (k = 0: every difference turns up), binary 0/255 (k = 1: the
		 * largest products, the sums' worst case), the moved texture (k = 2: converging
		 * tracks).
		 */
		for (int l = 0; l <= LEVELS; l++) {
			if (k == 2) {
				render(&I_[l], &I[l], l, 0, 0);
				render(&J_[l], &J[l], l, 2.7, -1.3);
				continue;
			}
			struct level *pair[2] = {&I_[l], &J_[l]};
			struct mvod_lk_level *out[2] = {&I[l], &J[l]};
			for (int m = 0; m < 2; m++) {
				pair[m]->w = W >> l;
				pair[m]->h = H >> l;
				for (size_t b = 0; b < sizeof(pair[m]->img); b++) {
					uint8_t v = (uint8_t)next_word(&seed);
					pair[m]->img[b] = k == 0 ? v : v & 1 ? 255 : 0;
				}
				scharr(pair[m], out[m]);
			}
		}
		random_points(&seed, from, guess);
		for (size_t w = 0; w < sizeof(wins) / sizeof(wins[0]); w++)
			for (int levels = 0; levels <= LEVELS; levels += LEVELS) {
				struct mvod_lk_params p = {.win = wins[w],
							   .levels = levels,
							   .iterations = 10,
							   .eps_px = 0.03f};
				compare_paths(&p, from, guess);
			}
	}
	print_message("compared with the plain C:%s%s\n",
		      paths_compared & 1 << MVOD_LK_VECTOR ? " vector (SSE2 or NEON)" : "",
		      paths_compared & 1 << MVOD_LK_AVX2 ? " AVX2" : "");
	assert_true(paths_compared & 1 << MVOD_LK_VECTOR);
}

/*
 * The texture moved by (2.7, -1.3) pixels, tracked from no guess (the points themselves) on
 * 3 levels: every point converges, to within BOUND_PX of the truth.
 */
static void track_shift(int win, double bound_px)
{
	const double dx = 2.7, dy = -1.3;
	render_pair(dx, dy);
	float from[2 * N], to[2 * N];
	uint8_t ok[N];
	int n = 0;
	for (int y = 20; y <= H - 20 && n < N; y += 8)
		for (int x = 20; x <= W - 20 && n < N; x += 8, n++) {
			/* Off the pixel grid: the template is interpolated. */
			from[2 * n] = to[2 * n] = (float)x + 0.37f;
			from[2 * n + 1] = to[2 * n + 1] = (float)y + 0.61f;
		}
	struct mvod_lk_params p = {.win = win, .levels = LEVELS, .iterations = 10, .eps_px = 0.03f};
	mvod_lk_flow(I, J, &p, from, to, n, ok);
	double worst = 0;
	for (int i = 0; i < n; i++) {
		assert_int_equal(ok[i], 1);
		worst = fmax(worst, hypot(to[2 * i] - from[2 * i] - dx,
					  to[2 * i + 1] - from[2 * i + 1] - dy));
	}
	print_message("win %d: %d points, worst error %.4f px\n", win, n, worst);
	assert_true(worst < bound_px);
}

/*
 * Bounds: about twice the worst error measured (0.009 px at 21 px, 0.029 at 9). What is left is
 * the texture's rounding to whole grey levels, bilinear interpolation of waves of 24 px and
 * more, and the stopping rule (a step under 0.03 px ends a level); a 9 px window averages less
 * of the first two than a 21 px one.
 */
static void test_subpixel_shift(void **state)
{
	(void)state;
	track_shift(21, 0.02);
	track_shift(9, 0.06);
}

/* A flat image: no gradient, the minimum eigenvalue test fails every point. */
static void test_flat_fails(void **state)
{
	(void)state;
	for (int l = 0; l <= LEVELS; l++) {
		struct level *pair[2] = {&I_[l], &J_[l]};
		struct mvod_lk_level *out[2] = {&I[l], &J[l]};
		for (int m = 0; m < 2; m++) {
			pair[m]->w = W >> l;
			pair[m]->h = H >> l;
			memset(pair[m]->img, 100, sizeof(pair[m]->img));
			scharr(pair[m], out[m]);
		}
	}
	float from[2] = {80.5f, 60.5f}, to[2] = {80.5f, 60.5f};
	uint8_t ok = 1;
	struct mvod_lk_params p = {.win = 21, .levels = LEVELS, .iterations = 10, .eps_px = 0.03f};
	mvod_lk_flow(I, J, &p, from, to, 1, &ok);
	assert_int_equal(ok, 0);
}

/* A guess whose window leaves the level and its border fails, where a near one converges. */
static void test_outside_fails(void **state)
{
	(void)state;
	render_pair(2.7, -1.3);
	float from[4] = {80.37f, 60.61f, 80.37f, 60.61f};
	float to[4] = {80.37f + 2.7f, 60.61f - 1.3f, (float)(W + BORDER), 60.61f};
	uint8_t ok[2] = {0, 1};
	struct mvod_lk_params p = {.win = 21, .levels = 0, .iterations = 10, .eps_px = 0.03f};
	mvod_lk_flow(I, J, &p, from, to, 2, ok);
	assert_int_equal(ok[0], 1);
	assert_int_equal(ok[1], 0);
}

/* Index i of n reflected about the edges (OpenCV's BORDER_REFLECT_101). */
static int reflect(int i, int n)
{
	return n == 1 ? 0 : i < 0 ? -i : i >= n ? 2 * n - 2 - i : i;
}

/*
 * Scharr derivatives: every path equals the plain C, and the plain C the 3x3 kernels over the
 * image reflected at its edges, on random images of many sizes (1 pixel to wider than two
 * AVX2 vectors, odd and even).
 */
static void test_scharr(void **state)
{
	(void)state;
	enum { SW = 45, SH = 7 };
	static const int sizes[][2] = {{1, 1},  {1, 5},  {2, 2},  {7, 3},  {8, 2},
				       {16, 4}, {17, 5}, {31, 6}, {33, 7}, {45, 7}};
	static uint8_t img[SH * SW];
	static int16_t ref[2 * SH * SW], out[2 * SH * SW], tmp[2 * (SW + 2)];
	uint64_t seed = 0x853c49e6748fea9bu;
	for (int k = 0; k < 20; k++) {
		for (size_t b = 0; b < sizeof(img); b++) {
			uint8_t v = (uint8_t)next_word(&seed);
			img[b] = k % 2 ? v : v & 1 ? 255 : 0;
		}
		for (size_t z = 0; z < sizeof(sizes) / sizeof(sizes[0]); z++) {
			int w = sizes[z][0], h = sizes[z][1];
			for (int y = 0; y < h; y++)
				for (int x = 0; x < w; x++) {
					int dx = 0, dy = 0;
					for (int j = -1; j <= 1; j++) {
						int wt = j ? 3 : 10;
						dx += wt * (img[reflect(y + j, h) * SW +
								reflect(x + 1, w)] -
							    img[reflect(y + j, h) * SW +
								reflect(x - 1, w)]);
						dy += wt * (img[reflect(y + 1, h) * SW +
								reflect(x + j, w)] -
							    img[reflect(y - 1, h) * SW +
								reflect(x + j, w)]);
					}
					ref[2 * (y * SW + x)] = (int16_t)dx;
					ref[2 * (y * SW + x) + 1] = (int16_t)dy;
				}
			for (int path = MVOD_LK_PLAIN; path <= MVOD_LK_AVX2; path++) {
				memset(out, 0x55, sizeof(out));
				if (mvod_lk_scharr_on((enum mvod_lk_path)path, img, SW, w, h, out,
						      2 * SW, tmp) == -ENOTSUP)
					continue;
				for (int y = 0; y < h; y++)
					if (memcmp(&out[2 * y * SW], &ref[2 * y * SW],
						   2 * (size_t)w * sizeof(int16_t)))
						fail_msg("scharr, path %d, %dx%d, row %d differs",
							 path, w, h, y);
			}
		}
	}
}

#ifdef MVOD_HAVE_OPENCV_LK
/*
 * Against OpenCV's own calcOpticalFlowPyrLK: where lk.c rejects a point and where it accepts
 * one, not only on flat patches. A 360 x 240 image, 8 x 6 blocks of 40 px, each one kind of
 * patch, and a flat margin 40 px wide on the right (below):
 *
 *   rows 0-2  low contrast: value noise (random grey levels on the pixel lattice, bilinear
 *             between them) of amplitude 0.25 .. 3.7 grey levels, block by block, across the
 *             amplitude where a 21 px window's smaller eigenvalue crosses OpenCV's 1e-4 (about
 *             1.7 grey levels here), so that both verdicts are decided there;
 *   rows 3-4  a straight step edge through the block at a random angle, 20-90 grey levels,
 *             blurred over EDGE_PX pixels as a lens blurs it: the aperture problem, one
 *             eigenvalue near zero, rejected (most by the determinant's test too, some by
 *             the minimum eigenvalue's alone);
 *   row 5     a corner (two perpendicular edges), well conditioned: accepted, and its sums
 *             are large enough (over 2^24) that the two trackers' float additions, made in
 *             another order, round differently.
 *
 * J is the same scene moved by (1.6, -0.7) px and rounded again. Five points a block, within
 * 5 px of its centre (a 21 px window stays inside the block), their guesses the shift plus up
 * to 1.5 px of error. lk.c's pyramids are built as the KLT front end builds them (klt_shim.h:
 * buildOpticalFlowPyramid, then lk.c's Scharr derivatives), OpenCV's by calcOpticalFlowPyrLK
 * from the images.
 *
 * The margin: lk.c reads a window's rows as whole vectors (the window rounded up to 8 pixels,
 * plus one), which must lie in the level and its border, where OpenCV only asks that the
 * window's corner lie in the level. On the right the two differ by up to 7 pixels, times 2^l
 * on level l: a 9 px window skips level 3 within about 40 px of the right edge where OpenCV
 * tracks on it (the point's status is the same, its position is not: 0.014 px here). Points
 * are kept out of that strip; inside the image at level 0, and on every other edge, the rules
 * agree.
 */
enum { BX = 8, BY = 6, CB = 40, CW = BX * CB + CB, CH = BY * CB, PER_BLOCK = 5 };
enum { CN = BX * BY * PER_BLOCK };
#define SHIFT_X 1.6
#define SHIFT_Y (-0.7)

struct patch {
	int kind; /* 0 low contrast, 1 edge, 2 corner */
	double amp; /* noise amplitude, or the edges' contrast, grey levels */
	double nx, ny, off; /* the edges' normal, and their offset from the block's centre */
};

static struct patch patches[BY][BX];
static float noise_lattice[(CH + 2) * (CW + 2)];
static uint8_t img_i[CH * CW], img_j[CH * CW];

/* A step blurred over EDGE_PX pixels, at signed distance d from its middle: 0 .. 1. */
#define EDGE_PX 4.0
static double ramp(double d)
{
	d /= EDGE_PX;
	return d < -0.5 ? 0 : d > 0.5 ? 1 : d + 0.5;
}

/* The scene's grey level at (x, y), any real position inside the image. */
static double scene(double x, double y)
{
	int bx = (int)floor(x / CB), by = (int)floor(y / CB);
	if (bx >= BX || bx < 0 || by < 0 || by >= BY)
		return 128;
	const struct patch *p = &patches[by][bx];
	double u = x - (bx + 0.5) * CB, v = y - (by + 0.5) * CB;
	if (p->kind == 0) {
		double fx = floor(x), fy = floor(y), a = x - fx, b = y - fy;
		const float *r0 = noise_lattice + ((int)fy + 1) * (CW + 2) + (int)fx + 1;
		const float *r1 = r0 + CW + 2;
		double n = (1 - a) * (1 - b) * r0[0] + a * (1 - b) * r0[1] + (1 - a) * b * r1[0] +
			   a * b * r1[1];
		return 128 + p->amp * n;
	}
	double d1 = p->nx * u + p->ny * v - p->off, d2 = -p->ny * u + p->nx * v - p->off;
	return 128 + p->amp * ((p->kind == 1 ? ramp(d1) : ramp(d1) * ramp(d2)) - 0.5);
}

static uint8_t grey(double v)
{
	return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : lrint(v));
}

/* A uniform double in [lo, hi], in steps of 1e-3. */
static double uniform(uint64_t *seed, double lo, double hi)
{
	return lo + (hi - lo) * (double)(next_word(seed) % 1001) / 1000.0;
}

/* The blocks' patches, the points (kind[i]: their block's) and the two images. */
static void make_scene(uint64_t *seed, float *from, float *guess, int *kind)
{
	for (size_t i = 0; i < sizeof(noise_lattice) / sizeof(noise_lattice[0]); i++)
		noise_lattice[i] = (float)uniform(seed, -1, 1);
	int k = 0;
	for (int by = 0; by < BY; by++)
		for (int bx = 0; bx < BX; bx++) {
			struct patch *p = &patches[by][bx];
			double th = uniform(seed, 0, 2 * M_PI);
			p->kind = by < 3 ? 0 : by < 5 ? 1 : 2;
			p->amp = p->kind == 0 ? 0.25 + 0.15 * (by * BX + bx) : uniform(seed, 20, 90);
			p->nx = cos(th);
			p->ny = sin(th);
			p->off = uniform(seed, -3, 3);
			for (int q = 0; q < PER_BLOCK; q++, k++) {
				kind[k] = p->kind;
				for (int c = 0; c < 2; c++) {
					double at = ((c ? by : bx) + 0.5) * CB + uniform(seed, -5, 5);
					from[2 * k + c] = (float)at;
					guess[2 * k + c] = (float)(at + (c ? SHIFT_Y : SHIFT_X) +
								   uniform(seed, -1.5, 1.5));
				}
			}
		}
	for (int y = 0; y < CH; y++)
		for (int x = 0; x < CW; x++) {
			img_i[y * CW + x] = grey(scene(x, y));
			img_j[y * CW + x] = grey(scene(x - SHIFT_X, y - SHIFT_Y));
		}
}

/* lk.c's tracker on path, on the pyramids the KLT front end builds for this window. */
static int lk_on_klt_pyramids(enum mvod_lk_path path, const struct mvod_lk_params *p,
			      const float *from, float *to, uint8_t *ok)
{
	struct mvod_klt_cv *k = NULL;
	struct mvod_lk_level li[4], lj[4];
	struct mvod_image a = {CW, CH, CW, MVOD_PIX_GREY, img_i};
	struct mvod_image b = {CW, CH, CW, MVOD_PIX_GREY, img_j};
	assert_int_equal(mvod_klt_cv_create(CW, CH, p->win, p->levels, 1, &k), 0);
	assert_int_equal(mvod_klt_cv_push(k, &a), 0);
	assert_int_equal(mvod_klt_cv_push(k, &b), 0);
	assert_int_equal(mvod_klt_cv_levels(k, 0, li, 4), p->levels + 1);
	assert_int_equal(mvod_klt_cv_levels(k, 1, lj, 4), p->levels + 1);
	int ret = mvod_lk_flow_on(path, li, lj, p, from, to, CN, ok);
	mvod_klt_cv_destroy(k);
	return ret;
}

/*
 * Every point's status is OpenCV's, on every path this machine has, and where both accept
 * the positions agree within 1e-4 px (lk.h; measured worst printed: 0 where every sum stays
 * under 2^24, an exact integer in both, 1.5e-5 px on the corners). With the windows and
 * levels the KLT front end runs: 21 px on 3 levels (a track without a predicted flow), 9 px on
 * 3 (the search with one), 21 px on level 0 alone (its refinement). The scene must hold both
 * verdicts where they are decided, or the equality says little: OpenCV accepts at least a
 * fifth and rejects at least a fifth of the low-contrast points, rejects every edge point and
 * accepts at least three quarters of the corner points (counts printed: a 9 px window around a
 * point 5 px from its corner may hold one edge only).
 */
static void test_status_equals_opencv(void **state)
{
	(void)state;
	static const struct mvod_lk_params cfg[] = {{21, 3, 10, 0.03f}, {9, 3, 10, 0.03f},
						    {21, 0, 10, 0.03f}};
	static float from[2 * CN], guess[2 * CN], ref[2 * CN], got[2 * CN];
	static uint8_t st_ref[CN], st_got[CN];
	static int kind[CN];
	uint64_t seed = 0x2545f4914f6cdd1du;
	make_scene(&seed, from, guess, kind);
	for (size_t c = 0; c < sizeof(cfg) / sizeof(cfg[0]); c++) {
		const struct mvod_lk_params *p = &cfg[c];
		memcpy(ref, guess, sizeof(ref));
		assert_int_equal(lk_opencv_flow(img_i, img_j, CW, CH, CW, p, from, ref, CN, st_ref),
				 0);
		int acc[3] = {0}, all[3] = {0};
		for (int i = 0; i < CN; i++) {
			acc[kind[i]] += st_ref[i] != 0;
			all[kind[i]]++;
		}
		print_message("win %d, levels %d: OpenCV accepts %d of %d low-contrast, %d of %d "
			      "edge, %d of %d corner points\n",
			      p->win, p->levels, acc[0], all[0], acc[1], all[1], acc[2], all[2]);
		assert_true(5 * acc[0] >= all[0] && 5 * (all[0] - acc[0]) >= all[0]);
		assert_int_equal(acc[1], 0);
		assert_true(4 * acc[2] >= 3 * all[2]);
		for (int path = MVOD_LK_PLAIN; path <= MVOD_LK_AVX2; path++) {
			memcpy(got, guess, sizeof(got));
			if (lk_on_klt_pyramids((enum mvod_lk_path)path, p, from, got, st_got) ==
			    -ENOTSUP)
				continue;
			double worst = 0;
			for (int i = 0; i < CN; i++) {
				if ((st_got[i] != 0) != (st_ref[i] != 0))
					fail_msg("win %d, levels %d, path %d, point %d (kind %d at "
						 "%.2f, %.2f): status %d, OpenCV's %d",
						 p->win, p->levels, path, i, kind[i], from[2 * i],
						 from[2 * i + 1], st_got[i], st_ref[i]);
				if (st_got[i])
					worst = fmax(worst, hypot(got[2 * i] - ref[2 * i],
								  got[2 * i + 1] - ref[2 * i + 1]));
			}
			print_message("  path %d: every status OpenCV's, positions within %.2g px\n",
				      path, worst);
			assert_true(worst <= 1e-4);
		}
	}
}
#endif

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_vector_equals_plain),
	    cmocka_unit_test(test_subpixel_shift),
	    cmocka_unit_test(test_flat_fails),
	    cmocka_unit_test(test_outside_fails),
	    cmocka_unit_test(test_scharr),
#ifdef MVOD_HAVE_OPENCV_LK
	    cmocka_unit_test(test_status_equals_opencv),
#endif
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
