#include "lk.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#if defined(__SSE2__)
#include <immintrin.h>
#elif defined(__ARM_NEON) && defined(__aarch64__)
#include <arm_neon.h>
#endif

/*
 * OpenCV's fixed point: bilinear weights of W_BITS bits, interpolated intensities with 5
 * fractional bits (the template is the pixel times 32), and the sums scaled by FLT_SCALE before
 * the minimum eigenvalue test, whose threshold is OpenCV's default.
 */
#define W_BITS 14
#define FRAC 5
#define FLT_SCALE (1.0f / (1 << 20))
#define MIN_EIG 1e-4f
/* OpenCV's test for a step that undoes the one before: half of it is taken back, and it stops. */
#define OSCILLATION_PX 0.01f

/*
 * A point's template on one level: win rows of pad int16 (win rounded up to 8), the pixel times
 * 32 and its Scharr derivatives, zero past column win (a padded column adds nothing to a sum).
 */
struct tmpl {
	int16_t t[MVOD_LK_MAX_WIN * MVOD_LK_MAX_WIN];
	int16_t x[MVOD_LK_MAX_WIN * MVOD_LK_MAX_WIN];
	int16_t y[MVOD_LK_MAX_WIN * MVOD_LK_MAX_WIN];
};

/*
 * Sums are kept in 4 lanes, lane l taking columns 8k + 2l and 8k + 2l + 1 of every 8 (the SSE2
 * multiply-add's pairs): each row's lane sums are exact integers (under 2^29: 4 blocks of 2
 * products of at most 8160 x 4080), converted to float and added to the lane's float, rows in
 * order, and the lanes are added as (0 + 1) + (2 + 3) at the end; every path does exactly that.
 */
static float lanes_sum(const float s[4])
{
	return (s[0] + s[1]) + (s[2] + s[3]);
}

/* The rectangle of wpx x hpx pixels at (x, y) lies in the level and its border. */
static bool fits(const struct mvod_lk_level *L, int x, int y, int wpx, int hpx)
{
	return x >= -L->border && y >= -L->border && x + wpx <= L->w + L->border &&
	       y + hpx <= L->h + L->border;
}

/* Index i of 0 .. n - 1 reflected about the edges (OpenCV's BORDER_REFLECT_101). */
static int reflect(int i, int n)
{
	return n == 1 ? 0 : i < 0 ? -i : i >= n ? 2 * n - 2 - i : i;
}

static int descale(int v, int bits)
{
	return (v + (1 << (bits - 1))) >> bits;
}

/* v rounded to the nearest integer, ties to even (lrintf's default), in one instruction. */
static int round_int(float v)
{
#if defined(__SSE2__)
	return _mm_cvtss_si32(_mm_set_ss(v));
#elif defined(__ARM_NEON) && defined(__aarch64__)
	return vcvtns_s32_f32(v);
#else
	return (int)lrintf(v);
#endif
}

/* Bilinear weights of W_BITS bits for fractions (a, b), as OpenCV rounds them. */
static void weights(float a, float b, int iw[4])
{
	iw[0] = round_int((1.f - a) * (1.f - b) * (1 << W_BITS));
	iw[1] = round_int(a * (1.f - b) * (1 << W_BITS));
	iw[2] = round_int((1.f - a) * b * (1 << W_BITS));
	iw[3] = (1 << W_BITS) - iw[0] - iw[1] - iw[2];
}

/* Pixel c of rows j0, j1 interpolated with weights iw, times 32 (FRAC bits). */
static int interp(const uint8_t *j0, const uint8_t *j1, int c, const int iw[4])
{
	return descale(j0[c] * iw[0] + j0[c + 1] * iw[1] + j1[c] * iw[2] + j1[c + 1] * iw[3],
		       W_BITS - FRAC);
}

/* Derivative k (0: d/dx, 1: d/dy) of pixel c of rows d0, d1 interpolated with weights iw. */
static int interp_deriv(const int16_t *d0, const int16_t *d1, int c, int k, const int iw[4])
{
	return descale(d0[2 * c + k] * iw[0] + d0[2 * c + 2 + k] * iw[1] + d1[2 * c + k] * iw[2] +
			   d1[2 * c + 2 + k] * iw[3],
		       W_BITS);
}

/*
 * The template: level L's pixels and derivatives from (tx, ty) interpolated with weights iw,
 * into T, with the lane sums of the derivatives' products: a[0] dx dx, a[1] dy dy, a[2] dx dy.
 */
static void prep_plain(const struct mvod_lk_level *L, int tx, int ty, const int iw[4], int win,
		       int pad, struct tmpl *T, float a[3][4])
{
	for (int k = 0; k < 3; k++)
		for (int l = 0; l < 4; l++)
			a[k][l] = 0;
	for (int r = 0; r < win; r++) {
		const uint8_t *s0 = L->img + (ptrdiff_t)(ty + r) * L->stride + tx,
			      *s1 = s0 + L->stride;
		const int16_t *d0 = L->deriv + (ptrdiff_t)(ty + r) * L->dstride + 2 * tx;
		const int16_t *d1 = d0 + L->dstride;
		int32_t sxx[4] = {0}, syy[4] = {0}, sxy[4] = {0};
		for (int c = 0; c < pad; c++) {
			int in = c < win, l = (c & 7) >> 1;
			int x = in ? interp_deriv(d0, d1, c, 0, iw) : 0;
			int y = in ? interp_deriv(d0, d1, c, 1, iw) : 0;
			T->t[r * pad + c] = (int16_t)(in ? interp(s0, s1, c, iw) : 0);
			T->x[r * pad + c] = (int16_t)x;
			T->y[r * pad + c] = (int16_t)y;
			sxx[l] += x * x;
			syy[l] += y * y;
			sxy[l] += x * y;
		}
		for (int l = 0; l < 4; l++) {
			a[0][l] += (float)sxx[l];
			a[1][l] += (float)syy[l];
			a[2][l] += (float)sxy[l];
		}
	}
}

/*
 * The lane sums of (J interpolated at (ix, iy) + fraction, weights iw) - template, times the
 * template's derivatives: b[0] along x, b[1] along y.
 */
static void mismatch_plain(const struct mvod_lk_level *L, int ix, int iy, const int iw[4], int win,
			   int pad, const struct tmpl *T, float b[2][4])
{
	for (int l = 0; l < 4; l++)
		b[0][l] = b[1][l] = 0;
	for (int r = 0; r < win; r++) {
		const uint8_t *j0 = L->img + (ptrdiff_t)(iy + r) * L->stride + ix,
			      *j1 = j0 + L->stride;
		int32_t s1[4] = {0}, s2[4] = {0};
		for (int c = 0; c < win; c++) {
			int diff = interp(j0, j1, c, iw) - T->t[r * pad + c], l = (c & 7) >> 1;
			s1[l] += diff * T->x[r * pad + c];
			s2[l] += diff * T->y[r * pad + c];
		}
		for (int l = 0; l < 4; l++) {
			b[0][l] += (float)s1[l];
			b[1][l] += (float)s2[l];
		}
	}
}

/*
 * Scharr derivatives, OpenCV's calcSharrDeriv to the bit: rows and columns past the edges
 * reflected about them (101), the vertical pass (3, 10, 3 and -1, 0, 1) into t0, t1 (a row of
 * w + 2, one before and one after), the horizontal one out as (d/dx, d/dy) pairs. Every value
 * fits int16 (at most 16 x 255).
 */
static void scharr_vertical_plain(const uint8_t *s0, const uint8_t *s1, const uint8_t *s2, int x,
				  int w, int16_t *t0, int16_t *t1)
{
	for (; x < w; x++) {
		t0[x] = (int16_t)((s0[x] + s2[x]) * 3 + s1[x] * 10);
		t1[x] = (int16_t)(s2[x] - s0[x]);
	}
}

static void scharr_horizontal_plain(const int16_t *t0, const int16_t *t1, int x, int w, int16_t *d)
{
	for (; x < w; x++) {
		d[2 * x] = (int16_t)(t0[x + 1] - t0[x - 1]);
		d[2 * x + 1] = (int16_t)((t1[x + 1] + t1[x - 1]) * 3 + t1[x] * 10);
	}
}

#if defined(__SSE2__)
/* Lanes 0 .. k - 1 of 8 int16: all ones; the rest zero. */
static __m128i first_lanes(int k)
{
	static const int16_t ones_zeros[16] = {-1, -1, -1, -1, -1, -1, -1, -1};
	return _mm_loadu_si128((const __m128i *)(ones_zeros + 8 - k));
}

/* Weights lo and hi as the int16 pair of one int32 lane; a weight may be -1 from the rounding. */
static int pair(int lo, int hi)
{
	return (int)((uint32_t)(lo & 0xffff) | (uint32_t)hi << 16);
}

/* (iw[0], iw[1]) and (iw[2], iw[3]) as int16 pairs. */
static void pair_weights(const int iw[4], __m128i *w0, __m128i *w1)
{
	*w0 = _mm_set1_epi32(pair(iw[0], iw[1]));
	*w1 = _mm_set1_epi32(pair(iw[2], iw[3]));
}

/*
 * Lane j: v00[j] iw[0] + v01[j] iw[1] + v10[j] iw[2] + v11[j] iw[3], descaled by bits (the
 * weights as pair_weights gives them).
 */
static __m128i blend8(__m128i v00, __m128i v01, __m128i v10, __m128i v11, __m128i w0, __m128i w1,
		      int bits)
{
	const __m128i half = _mm_set1_epi32(1 << (bits - 1));
	__m128i t0 = _mm_add_epi32(_mm_madd_epi16(_mm_unpacklo_epi16(v00, v01), w0),
				   _mm_madd_epi16(_mm_unpacklo_epi16(v10, v11), w1));
	__m128i t1 = _mm_add_epi32(_mm_madd_epi16(_mm_unpackhi_epi16(v00, v01), w0),
				   _mm_madd_epi16(_mm_unpackhi_epi16(v10, v11), w1));
	return _mm_packs_epi32(_mm_srai_epi32(_mm_add_epi32(t0, half), bits),
			       _mm_srai_epi32(_mm_add_epi32(t1, half), bits));
}

static __m128i load8(const uint8_t *p)
{
	return _mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)p), _mm_setzero_si128());
}

/* interp() of pixels c .. c + 7 (reads c .. c + 8 of both rows). */
static __m128i interp8(const uint8_t *j0, const uint8_t *j1, int c, __m128i w0, __m128i w1)
{
	return blend8(load8(j0 + c), load8(j0 + c + 1), load8(j1 + c), load8(j1 + c + 1), w0, w1,
		      W_BITS - FRAC);
}

/*
 * interp_deriv() of pixels c .. c + 3 as (d/dx, d/dy) pairs: 4 pairs of rows d0, d1 from pair
 * c on, and 4 from pair c + 1 on, as OpenCV's tracker does it.
 */
static __m128i interp_deriv4(const int16_t *d0, const int16_t *d1, int c, __m128i w0, __m128i w1)
{
	return blend8(_mm_loadu_si128((const __m128i *)(d0 + 2 * c)),
		      _mm_loadu_si128((const __m128i *)(d0 + 2 * c + 2)),
		      _mm_loadu_si128((const __m128i *)(d1 + 2 * c)),
		      _mm_loadu_si128((const __m128i *)(d1 + 2 * c + 2)), w0, w1, W_BITS);
}

/* The 8 int16 of pairs from p on and from p + 8 on, split: d/dx into *x, d/dy into *y. */
static void split_pairs(__m128i d0, __m128i d1, __m128i *x, __m128i *y)
{
	*x = _mm_packs_epi32(_mm_srai_epi32(_mm_slli_epi32(d0, 16), 16),
			     _mm_srai_epi32(_mm_slli_epi32(d1, 16), 16));
	*y = _mm_packs_epi32(_mm_srai_epi32(d0, 16), _mm_srai_epi32(d1, 16));
}

/*
 * Both vector preps: row r's 8 pixels from column c (t, x, y; the last block's lanes past win
 * zeroed by tail) into T, their products into the lane sums.
 */
static void prep_store(struct tmpl *T, int r, int c, int pad, __m128i tail, __m128i t, __m128i x,
		       __m128i y, __m128i *sxx, __m128i *syy, __m128i *sxy)
{
	if (c + 8 == pad) {
		t = _mm_and_si128(t, tail);
		x = _mm_and_si128(x, tail);
		y = _mm_and_si128(y, tail);
	}
	_mm_storeu_si128((__m128i *)(T->t + r * pad + c), t);
	_mm_storeu_si128((__m128i *)(T->x + r * pad + c), x);
	_mm_storeu_si128((__m128i *)(T->y + r * pad + c), y);
	*sxx = _mm_add_epi32(*sxx, _mm_madd_epi16(x, x));
	*syy = _mm_add_epi32(*syy, _mm_madd_epi16(y, y));
	*sxy = _mm_add_epi32(*sxy, _mm_madd_epi16(x, y));
}

static void prep_vec(const struct mvod_lk_level *L, int tx, int ty, const int iw[4], int win,
		     int pad, struct tmpl *T, float a[3][4])
{
	const __m128i z = _mm_setzero_si128(), tail = first_lanes(win - (pad - 8));
	__m128i w0, w1;
	pair_weights(iw, &w0, &w1);
	__m128 axx = _mm_setzero_ps(), ayy = axx, axy = axx;
	for (int r = 0; r < win; r++) {
		const uint8_t *s0 = L->img + (ptrdiff_t)(ty + r) * L->stride + tx,
			      *s1 = s0 + L->stride;
		const int16_t *e0 = L->deriv + (ptrdiff_t)(ty + r) * L->dstride + 2 * tx;
		const int16_t *e1 = e0 + L->dstride;
		__m128i sxx = z, syy = z, sxy = z, t, x, y;
		for (int c = 0; c < pad; c += 8) {
			t = interp8(s0, s1, c, w0, w1);
			split_pairs(interp_deriv4(e0, e1, c, w0, w1),
				    interp_deriv4(e0, e1, c + 4, w0, w1), &x, &y);
			prep_store(T, r, c, pad, tail, t, x, y, &sxx, &syy, &sxy);
		}
		axx = _mm_add_ps(axx, _mm_cvtepi32_ps(sxx));
		ayy = _mm_add_ps(ayy, _mm_cvtepi32_ps(syy));
		axy = _mm_add_ps(axy, _mm_cvtepi32_ps(sxy));
	}
	_mm_storeu_ps(a[0], axx);
	_mm_storeu_ps(a[1], ayy);
	_mm_storeu_ps(a[2], axy);
}

static void mismatch_vec(const struct mvod_lk_level *L, int ix, int iy, const int iw[4], int win,
			 int pad, const struct tmpl *T, float b[2][4])
{
	const __m128i z = _mm_setzero_si128();
	__m128i w0, w1;
	pair_weights(iw, &w0, &w1);
	__m128 b1 = _mm_setzero_ps(), b2 = b1;
	for (int r = 0; r < win; r++) {
		const uint8_t *j0 = L->img + (ptrdiff_t)(iy + r) * L->stride + ix,
			      *j1 = j0 + L->stride;
		__m128i s1 = z, s2 = z;
		for (int c = 0; c < pad; c += 8) {
			__m128i diff =
			    _mm_sub_epi16(interp8(j0, j1, c, w0, w1),
					  _mm_loadu_si128((const __m128i *)(T->t + r * pad + c)));
			s1 = _mm_add_epi32(
			    s1, _mm_madd_epi16(
				    diff, _mm_loadu_si128((const __m128i *)(T->x + r * pad + c))));
			s2 = _mm_add_epi32(
			    s2, _mm_madd_epi16(
				    diff, _mm_loadu_si128((const __m128i *)(T->y + r * pad + c))));
		}
		b1 = _mm_add_ps(b1, _mm_cvtepi32_ps(s1));
		b2 = _mm_add_ps(b2, _mm_cvtepi32_ps(s2));
	}
	_mm_storeu_ps(b[0], b1);
	_mm_storeu_ps(b[1], b2);
}

/* The Scharr passes 8 pixels at a time from x on; returns where they stopped. */
static int scharr_vertical_vec(const uint8_t *s0, const uint8_t *s1, const uint8_t *s2, int w,
			       int16_t *t0, int16_t *t1)
{
	const __m128i three = _mm_set1_epi16(3), ten = _mm_set1_epi16(10);
	int x = 0;
	for (; x + 8 <= w; x += 8) {
		__m128i a = load8(s0 + x), b = load8(s1 + x), c = load8(s2 + x);
		_mm_storeu_si128((__m128i *)(t0 + x),
				 _mm_add_epi16(_mm_mullo_epi16(_mm_add_epi16(a, c), three),
					       _mm_mullo_epi16(b, ten)));
		_mm_storeu_si128((__m128i *)(t1 + x), _mm_sub_epi16(c, a));
	}
	return x;
}

static int scharr_horizontal_vec(const int16_t *t0, const int16_t *t1, int w, int16_t *d)
{
	const __m128i three = _mm_set1_epi16(3), ten = _mm_set1_epi16(10);
	int x = 0;
	for (; x + 8 <= w; x += 8) {
		__m128i dx = _mm_sub_epi16(_mm_loadu_si128((const __m128i *)(t0 + x + 1)),
					   _mm_loadu_si128((const __m128i *)(t0 + x - 1)));
		__m128i dy = _mm_add_epi16(
		    _mm_mullo_epi16(_mm_add_epi16(_mm_loadu_si128((const __m128i *)(t1 + x + 1)),
						  _mm_loadu_si128((const __m128i *)(t1 + x - 1))),
				    three),
		    _mm_mullo_epi16(_mm_loadu_si128((const __m128i *)(t1 + x)), ten));
		_mm_storeu_si128((__m128i *)(d + 2 * x), _mm_unpacklo_epi16(dx, dy));
		_mm_storeu_si128((__m128i *)(d + 2 * x + 8), _mm_unpackhi_epi16(dx, dy));
	}
	return x;
}

#if defined(__x86_64__) && defined(__GNUC__)
/*
 * AVX2 (chosen at run time, mvod_lk_flow): 16 pixels a vector. A row's 16-pixel blocks give 8
 * lane sums, the second 4 of them columns 8 .. 15's pairs, folded onto the first 4 as exact
 * integers before the row's float addition: the same lane sums as the 8-pixel paths.
 */
#define HAVE_AVX2 1
#define AVX2 __attribute__((target("avx2")))

/* Lanes 0 .. k - 1 of 16 int16: all ones; the rest zero. */
AVX2 static __m256i first_lanes16(int k)
{
	static const int16_t ones_zeros[32] = {-1, -1, -1, -1, -1, -1, -1, -1,
					       -1, -1, -1, -1, -1, -1, -1, -1};
	return _mm256_loadu_si256((const __m256i *)(ones_zeros + 16 - k));
}

/* The sums of both halves' lanes. */
AVX2 static __m128i fold(__m256i v)
{
	return _mm_add_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
}

/* Lane j: v00[j] iw[0] + v01[j] iw[1] + v10[j] iw[2] + v11[j] iw[3], descaled by bits. */
AVX2 static __m256i blend16(__m256i v00, __m256i v01, __m256i v10, __m256i v11, __m256i w0,
			    __m256i w1, int bits)
{
	const __m256i half = _mm256_set1_epi32(1 << (bits - 1));
	__m256i t0 = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpacklo_epi16(v00, v01), w0),
				      _mm256_madd_epi16(_mm256_unpacklo_epi16(v10, v11), w1));
	__m256i t1 = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpackhi_epi16(v00, v01), w0),
				      _mm256_madd_epi16(_mm256_unpackhi_epi16(v10, v11), w1));
	/* unpack and pack both work within halves: the order comes back */
	return _mm256_packs_epi32(_mm256_srai_epi32(_mm256_add_epi32(t0, half), bits),
				  _mm256_srai_epi32(_mm256_add_epi32(t1, half), bits));
}

AVX2 static __m256i load16(const uint8_t *p)
{
	return _mm256_cvtepu8_epi16(_mm_loadu_si128((const __m128i *)p));
}

/* interp() of pixels c .. c + 15. */
AVX2 static __m256i interp16(const uint8_t *j0, const uint8_t *j1, int c, __m256i w0, __m256i w1)
{
	return blend16(load16(j0 + c), load16(j0 + c + 1), load16(j1 + c), load16(j1 + c + 1), w0,
		       w1, W_BITS - FRAC);
}

/* interp_deriv() of pixels c .. c + 7 as (d/dx, d/dy) pairs. */
AVX2 static __m256i interp_deriv8(const int16_t *d0, const int16_t *d1, int c, __m256i w0,
				  __m256i w1)
{
	return blend16(_mm256_loadu_si256((const __m256i *)(d0 + 2 * c)),
		       _mm256_loadu_si256((const __m256i *)(d0 + 2 * c + 2)),
		       _mm256_loadu_si256((const __m256i *)(d1 + 2 * c)),
		       _mm256_loadu_si256((const __m256i *)(d1 + 2 * c + 2)), w0, w1, W_BITS);
}

AVX2 static void pair_weights16(const int iw[4], __m256i *w0, __m256i *w1)
{
	*w0 = _mm256_set1_epi32(pair(iw[0], iw[1]));
	*w1 = _mm256_set1_epi32(pair(iw[2], iw[3]));
}

AVX2 static void prep_avx2(const struct mvod_lk_level *L, int tx, int ty, const int iw[4], int win,
			   int pad, struct tmpl *T, float a[3][4])
{
	const __m128i tail = first_lanes(win - (pad - 8));
	const __m256i tail16 = first_lanes16(win - (pad - 16 > 0 ? pad - 16 : 0));
	__m128i w0, w1;
	__m256i v0, v1;
	pair_weights(iw, &w0, &w1);
	pair_weights16(iw, &v0, &v1);
	__m128 axx = _mm_setzero_ps(), ayy = axx, axy = axx;
	for (int r = 0; r < win; r++) {
		const uint8_t *s0 = L->img + (ptrdiff_t)(ty + r) * L->stride + tx,
			      *s1 = s0 + L->stride;
		const int16_t *e0 = L->deriv + (ptrdiff_t)(ty + r) * L->dstride + 2 * tx;
		const int16_t *e1 = e0 + L->dstride;
		__m256i hxx = _mm256_setzero_si256(), hyy = hxx, hxy = hxx;
		int c = 0;
		for (; c + 16 <= pad; c += 16) {
			__m256i t = interp16(s0, s1, c, v0, v1);
			__m256i d0 = interp_deriv8(e0, e1, c, v0, v1),
				d1 = interp_deriv8(e0, e1, c + 8, v0, v1);
			__m256i x =
			    _mm256_packs_epi32(_mm256_srai_epi32(_mm256_slli_epi32(d0, 16), 16),
					       _mm256_srai_epi32(_mm256_slli_epi32(d1, 16), 16));
			__m256i y = _mm256_packs_epi32(_mm256_srai_epi32(d0, 16),
						       _mm256_srai_epi32(d1, 16));
			/* packs took d0's and d1's halves in turn: pixels 0-3, 8-11, 4-7, 12-15 */
			x = _mm256_permute4x64_epi64(x, 0xd8);
			y = _mm256_permute4x64_epi64(y, 0xd8);
			if (c + 16 == pad) {
				t = _mm256_and_si256(t, tail16);
				x = _mm256_and_si256(x, tail16);
				y = _mm256_and_si256(y, tail16);
			}
			_mm256_storeu_si256((__m256i *)(T->t + r * pad + c), t);
			_mm256_storeu_si256((__m256i *)(T->x + r * pad + c), x);
			_mm256_storeu_si256((__m256i *)(T->y + r * pad + c), y);
			hxx = _mm256_add_epi32(hxx, _mm256_madd_epi16(x, x));
			hyy = _mm256_add_epi32(hyy, _mm256_madd_epi16(y, y));
			hxy = _mm256_add_epi32(hxy, _mm256_madd_epi16(x, y));
		}
		__m128i sxx = fold(hxx), syy = fold(hyy), sxy = fold(hxy), x, y;
		if (c < pad) {
			split_pairs(interp_deriv4(e0, e1, c, w0, w1),
				    interp_deriv4(e0, e1, c + 4, w0, w1), &x, &y);
			prep_store(T, r, c, pad, tail, interp8(s0, s1, c, w0, w1), x, y, &sxx, &syy,
				   &sxy);
		}
		axx = _mm_add_ps(axx, _mm_cvtepi32_ps(sxx));
		ayy = _mm_add_ps(ayy, _mm_cvtepi32_ps(syy));
		axy = _mm_add_ps(axy, _mm_cvtepi32_ps(sxy));
	}
	_mm_storeu_ps(a[0], axx);
	_mm_storeu_ps(a[1], ayy);
	_mm_storeu_ps(a[2], axy);
}

AVX2 static void mismatch_avx2(const struct mvod_lk_level *L, int ix, int iy, const int iw[4],
			       int win, int pad, const struct tmpl *T, float b[2][4])
{
	__m128i w0, w1;
	__m256i v0, v1;
	pair_weights(iw, &w0, &w1);
	pair_weights16(iw, &v0, &v1);
	/* b[0]'s lanes, then b[1]'s: each row's two sums folded and converted in one vector */
	__m256 acc = _mm256_setzero_ps();
	for (int r = 0; r < win; r++) {
		const uint8_t *j0 = L->img + (ptrdiff_t)(iy + r) * L->stride + ix,
			      *j1 = j0 + L->stride;
		const int16_t *t = T->t + r * pad, *x = T->x + r * pad, *y = T->y + r * pad;
		__m256i h1 = _mm256_setzero_si256(), h2 = h1;
		int c = 0;
		for (; c + 16 <= pad; c += 16) {
			__m256i diff =
			    _mm256_sub_epi16(interp16(j0, j1, c, v0, v1),
					     _mm256_loadu_si256((const __m256i *)(t + c)));
			h1 = _mm256_add_epi32(
			    h1,
			    _mm256_madd_epi16(diff, _mm256_loadu_si256((const __m256i *)(x + c))));
			h2 = _mm256_add_epi32(
			    h2,
			    _mm256_madd_epi16(diff, _mm256_loadu_si256((const __m256i *)(y + c))));
		}
		__m256i s12 = _mm256_add_epi32(_mm256_permute2x128_si256(h1, h2, 0x20),
					       _mm256_permute2x128_si256(h1, h2, 0x31));
		if (c < pad) {
			__m128i diff = _mm_sub_epi16(interp8(j0, j1, c, w0, w1),
						     _mm_loadu_si128((const __m128i *)(t + c)));
			__m128i m1 =
			    _mm_madd_epi16(diff, _mm_loadu_si128((const __m128i *)(x + c)));
			__m128i m2 =
			    _mm_madd_epi16(diff, _mm_loadu_si128((const __m128i *)(y + c)));
			s12 = _mm256_add_epi32(s12, _mm256_set_m128i(m2, m1));
		}
		acc = _mm256_add_ps(acc, _mm256_cvtepi32_ps(s12));
	}
	_mm_storeu_ps(b[0], _mm256_castps256_ps128(acc));
	_mm_storeu_ps(b[1], _mm256_extractf128_ps(acc, 1));
}

AVX2 static int scharr_vertical_avx2(const uint8_t *s0, const uint8_t *s1, const uint8_t *s2, int w,
				     int16_t *t0, int16_t *t1)
{
	const __m256i three = _mm256_set1_epi16(3), ten = _mm256_set1_epi16(10);
	int x = 0;
	for (; x + 16 <= w; x += 16) {
		__m256i a = load16(s0 + x), b = load16(s1 + x), c = load16(s2 + x);
		_mm256_storeu_si256(
		    (__m256i *)(t0 + x),
		    _mm256_add_epi16(_mm256_mullo_epi16(_mm256_add_epi16(a, c), three),
				     _mm256_mullo_epi16(b, ten)));
		_mm256_storeu_si256((__m256i *)(t1 + x), _mm256_sub_epi16(c, a));
	}
	return x + scharr_vertical_vec(s0 + x, s1 + x, s2 + x, w - x, t0 + x, t1 + x);
}

AVX2 static int scharr_horizontal_avx2(const int16_t *t0, const int16_t *t1, int w, int16_t *d)
{
	const __m256i three = _mm256_set1_epi16(3), ten = _mm256_set1_epi16(10);
	int x = 0;
	for (; x + 16 <= w; x += 16) {
		__m256i dx = _mm256_sub_epi16(_mm256_loadu_si256((const __m256i *)(t0 + x + 1)),
					      _mm256_loadu_si256((const __m256i *)(t0 + x - 1)));
		__m256i sum = _mm256_add_epi16(_mm256_loadu_si256((const __m256i *)(t1 + x + 1)),
					       _mm256_loadu_si256((const __m256i *)(t1 + x - 1)));
		__m256i dy = _mm256_add_epi16(
		    _mm256_mullo_epi16(sum, three),
		    _mm256_mullo_epi16(_mm256_loadu_si256((const __m256i *)(t1 + x)), ten));
		/* unpack works within halves: pixels 0-3 | 8-11 and 4-7 | 12-15 */
		__m256i lo = _mm256_unpacklo_epi16(dx, dy), hi = _mm256_unpackhi_epi16(dx, dy);
		_mm256_storeu_si256((__m256i *)(d + 2 * x),
				    _mm256_permute2x128_si256(lo, hi, 0x20));
		_mm256_storeu_si256((__m256i *)(d + 2 * x + 16),
				    _mm256_permute2x128_si256(lo, hi, 0x31));
	}
	return x + scharr_horizontal_vec(t0 + x, t1 + x, w - x, d + 2 * x);
}

#endif

#elif defined(__ARM_NEON) && defined(__aarch64__)
/* Lanes 0 .. k - 1 of 8 int16: all ones; the rest zero. */
static int16x8_t first_lanes(int k)
{
	static const int16_t ones_zeros[16] = {-1, -1, -1, -1, -1, -1, -1, -1};
	return vld1q_s16(ones_zeros + 8 - k);
}

/* SSE2's multiply-add: lane l = a[2l] b[2l] + a[2l + 1] b[2l + 1]. */
static int32x4_t madd(int16x8_t a, int16x8_t b)
{
	return vpaddq_s32(vmull_s16(vget_low_s16(a), vget_low_s16(b)), vmull_high_s16(a, b));
}

/* Lane j: a[j] w0 + b[j] w1 + c[j] w2 + d[j] w3, rounded and shifted right by bits. */
static int16x8_t blend(int16x8_t a, int16x8_t b, int16x8_t c, int16x8_t d, const int16_t w[4],
		       int bits)
{
	int32x4_t lo = vmull_n_s16(vget_low_s16(a), w[0]), hi = vmull_high_n_s16(a, w[0]);
	lo = vmlal_n_s16(lo, vget_low_s16(b), w[1]);
	hi = vmlal_high_n_s16(hi, b, w[1]);
	lo = vmlal_n_s16(lo, vget_low_s16(c), w[2]);
	hi = vmlal_high_n_s16(hi, c, w[2]);
	lo = vmlal_n_s16(lo, vget_low_s16(d), w[3]);
	hi = vmlal_high_n_s16(hi, d, w[3]);
	int32x4_t r = vdupq_n_s32(1 << (bits - 1));
	/* (v + 2^(bits-1)) >> bits, as descale(); the sums fit int32, their halves int16 */
	lo = vshlq_s32(vaddq_s32(lo, r), vdupq_n_s32(-bits));
	hi = vshlq_s32(vaddq_s32(hi, r), vdupq_n_s32(-bits));
	return vcombine_s16(vmovn_s32(lo), vmovn_s32(hi));
}

static int16x8_t load8(const uint8_t *p)
{
	return vreinterpretq_s16_u16(vmovl_u8(vld1_u8(p)));
}

/* interp() of pixels c .. c + 7 (reads c .. c + 8 of both rows). */
static int16x8_t interp8(const uint8_t *j0, const uint8_t *j1, int c, const int16_t w[4])
{
	return blend(load8(j0 + c), load8(j0 + c + 1), load8(j1 + c), load8(j1 + c + 1), w,
		     W_BITS - FRAC);
}

/* interp_deriv() of pixels c .. c + 3 as (d/dx, d/dy) pairs. */
static int16x8_t interp_deriv4(const int16_t *d0, const int16_t *d1, int c, const int16_t w[4])
{
	return blend(vld1q_s16(d0 + 2 * c), vld1q_s16(d0 + 2 * c + 2), vld1q_s16(d1 + 2 * c),
		     vld1q_s16(d1 + 2 * c + 2), w, W_BITS);
}

static void prep_vec(const struct mvod_lk_level *L, int tx, int ty, const int iw[4], int win,
		     int pad, struct tmpl *T, float a[3][4])
{
	const int16x8_t tail = first_lanes(win - (pad - 8));
	const int16_t w[4] = {(int16_t)iw[0], (int16_t)iw[1], (int16_t)iw[2], (int16_t)iw[3]};
	float32x4_t axx = vdupq_n_f32(0), ayy = axx, axy = axx;
	for (int r = 0; r < win; r++) {
		const uint8_t *s0 = L->img + (ptrdiff_t)(ty + r) * L->stride + tx,
			      *s1 = s0 + L->stride;
		const int16_t *e0 = L->deriv + (ptrdiff_t)(ty + r) * L->dstride + 2 * tx;
		const int16_t *e1 = e0 + L->dstride;
		int32x4_t sxx = vdupq_n_s32(0), syy = sxx, sxy = sxx;
		for (int c = 0; c < pad; c += 8) {
			int16x8_t t = interp8(s0, s1, c, w), d0 = interp_deriv4(e0, e1, c, w);
			int16x8_t d1 = interp_deriv4(e0, e1, c + 4, w);
			int16x8_t x = vuzp1q_s16(d0, d1), y = vuzp2q_s16(d0, d1);
			if (c + 8 == pad) {
				t = vandq_s16(t, tail);
				x = vandq_s16(x, tail);
				y = vandq_s16(y, tail);
			}
			vst1q_s16(T->t + r * pad + c, t);
			vst1q_s16(T->x + r * pad + c, x);
			vst1q_s16(T->y + r * pad + c, y);
			sxx = vaddq_s32(sxx, madd(x, x));
			syy = vaddq_s32(syy, madd(y, y));
			sxy = vaddq_s32(sxy, madd(x, y));
		}
		axx = vaddq_f32(axx, vcvtq_f32_s32(sxx));
		ayy = vaddq_f32(ayy, vcvtq_f32_s32(syy));
		axy = vaddq_f32(axy, vcvtq_f32_s32(sxy));
	}
	vst1q_f32(a[0], axx);
	vst1q_f32(a[1], ayy);
	vst1q_f32(a[2], axy);
}

static void mismatch_vec(const struct mvod_lk_level *L, int ix, int iy, const int iw[4], int win,
			 int pad, const struct tmpl *T, float b[2][4])
{
	const int16_t w[4] = {(int16_t)iw[0], (int16_t)iw[1], (int16_t)iw[2], (int16_t)iw[3]};
	float32x4_t b1 = vdupq_n_f32(0), b2 = b1;
	for (int r = 0; r < win; r++) {
		const uint8_t *j0 = L->img + (ptrdiff_t)(iy + r) * L->stride + ix,
			      *j1 = j0 + L->stride;
		int32x4_t s1 = vdupq_n_s32(0), s2 = s1;
		for (int c = 0; c < pad; c += 8) {
			int16x8_t diff =
			    vsubq_s16(interp8(j0, j1, c, w), vld1q_s16(T->t + r * pad + c));
			s1 = vaddq_s32(s1, madd(diff, vld1q_s16(T->x + r * pad + c)));
			s2 = vaddq_s32(s2, madd(diff, vld1q_s16(T->y + r * pad + c)));
		}
		b1 = vaddq_f32(b1, vcvtq_f32_s32(s1));
		b2 = vaddq_f32(b2, vcvtq_f32_s32(s2));
	}
	vst1q_f32(b[0], b1);
	vst1q_f32(b[1], b2);
}

static int scharr_vertical_vec(const uint8_t *s0, const uint8_t *s1, const uint8_t *s2, int w,
			       int16_t *t0, int16_t *t1)
{
	int x = 0;
	for (; x + 8 <= w; x += 8) {
		int16x8_t a = load8(s0 + x), b = load8(s1 + x), c = load8(s2 + x);
		vst1q_s16(t0 + x, vaddq_s16(vmulq_n_s16(vaddq_s16(a, c), 3), vmulq_n_s16(b, 10)));
		vst1q_s16(t1 + x, vsubq_s16(c, a));
	}
	return x;
}

static int scharr_horizontal_vec(const int16_t *t0, const int16_t *t1, int w, int16_t *d)
{
	int x = 0;
	for (; x + 8 <= w; x += 8) {
		int16x8x2_t p;
		p.val[0] = vsubq_s16(vld1q_s16(t0 + x + 1), vld1q_s16(t0 + x - 1));
		p.val[1] = vaddq_s16(
		    vmulq_n_s16(vaddq_s16(vld1q_s16(t1 + x + 1), vld1q_s16(t1 + x - 1)), 3),
		    vmulq_n_s16(vld1q_s16(t1 + x), 10));
		vst2q_s16(d + 2 * x, p); /* interleaved: (d/dx, d/dy) pairs */
	}
	return x;
}

#else
#define prep_vec prep_plain
#define mismatch_vec mismatch_plain
static int scharr_vertical_vec(const uint8_t *s0, const uint8_t *s1, const uint8_t *s2, int w,
			       int16_t *t0, int16_t *t1)
{
	(void)s0, (void)s1, (void)s2, (void)w, (void)t0, (void)t1;
	return 0;
}

static int scharr_horizontal_vec(const int16_t *t0, const int16_t *t1, int w, int16_t *d)
{
	(void)t0, (void)t1, (void)w, (void)d;
	return 0;
}
#endif

/* A path's two kernels. */
struct kernels {
	void (*prep)(const struct mvod_lk_level *L, int tx, int ty, const int iw[4], int win,
		     int pad, struct tmpl *T, float a[3][4]);
	void (*mismatch)(const struct mvod_lk_level *L, int ix, int iy, const int iw[4], int win,
			 int pad, const struct tmpl *T, float b[2][4]);
};

/*
 * One point through every level (OpenCV's LKTrackerInvoker). The window's corner (fx, fy) is
 * what a step moves, and the centre (nx, ny) follows it, as OpenCV's nextPt and nextPts do:
 * moving the centre and taking the corner from it rounds otherwise in the last bit, which the
 * next bilinear weights' rounding can grow into much of a step (against OpenCV up to 3e-3 px
 * on low-contrast patches and 6e-4 px on corners, where this gives 0 and 1.5e-5 px:
 * tests/unit/test_lk.c).
 */
static void track(const struct mvod_lk_level *I, const struct mvod_lk_level *J,
		  const struct mvod_lk_params *p, const float *from, float *to, uint8_t *ok,
		  const struct kernels *k, struct tmpl *T)
{
	int win = p->win, pad = (win + 7) & ~7, status = 1;
	float half = (float)(win - 1) * 0.5f, nx = 0, ny = 0;
	double eps2 = (double)p->eps_px * p->eps_px;
	for (int lv = p->levels; lv >= 0; lv--) {
		const struct mvod_lk_level *li = &I[lv], *lj = &J[lv];
		float sc = (float)(1.0 / (1 << lv)), px = from[0] * sc, py = from[1] * sc;
		nx = lv == p->levels ? to[0] * sc : nx * 2;
		ny = lv == p->levels ? to[1] * sc : ny * 2;
		float wx = px - half, wy = py - half;
		int tx = (int)floorf(wx), ty = (int)floorf(wy), iw[4];
		if (!fits(li, tx, ty, pad + 1, win + 1)) {
			status &= lv > 0;
			continue;
		}
		weights(wx - (float)tx, wy - (float)ty, iw);
		float a[3][4];
		k->prep(li, tx, ty, iw, win, pad, T, a);
		float a11 = lanes_sum(a[0]) * FLT_SCALE, a22 = lanes_sum(a[1]) * FLT_SCALE;
		float a12 = lanes_sum(a[2]) * FLT_SCALE, det = a11 * a22 - a12 * a12;
		float min_eig = (a22 + a11 - sqrtf((a11 - a22) * (a11 - a22) + 4.f * a12 * a12)) /
				(float)(2 * win * win);
		if (min_eig < MIN_EIG || det < FLT_EPSILON) {
			status &= lv > 0;
			continue;
		}
		float inv = 1.f / det, pdx = 0, pdy = 0, fx = nx - half, fy = ny - half;
		for (int j = 0; j < p->iterations; j++) {
			int ix = (int)floorf(fx), iy = (int)floorf(fy);
			if (!fits(lj, ix, iy, pad + 1, win + 1)) {
				status &= lv > 0;
				break;
			}
			weights(fx - (float)ix, fy - (float)iy, iw);
			float b[2][4];
			k->mismatch(lj, ix, iy, iw, win, pad, T, b);
			float b1 = lanes_sum(b[0]) * FLT_SCALE, b2 = lanes_sum(b[1]) * FLT_SCALE;
			float dx = (a12 * b2 - a22 * b1) * inv, dy = (a12 * b1 - a11 * b2) * inv;
			fx += dx;
			fy += dy;
			nx = fx + half;
			ny = fy + half;
			if ((double)dx * dx + (double)dy * dy <= eps2)
				break;
			if (j > 0 && fabsf(dx + pdx) < OSCILLATION_PX &&
			    fabsf(dy + pdy) < OSCILLATION_PX) {
				nx -= dx * 0.5f;
				ny -= dy * 0.5f;
				break;
			}
			pdx = dx;
			pdy = dy;
		}
	}
	to[0] = nx;
	to[1] = ny;
	*ok = (uint8_t)status;
}

int mvod_lk_flow_on(enum mvod_lk_path path, const struct mvod_lk_level *I,
		    const struct mvod_lk_level *J, const struct mvod_lk_params *p,
		    const float *from, float *to, int n, uint8_t *ok)
{
	static const struct kernels plain = {prep_plain, mismatch_plain},
				    vec = {prep_vec, mismatch_vec};
	const struct kernels *k = path == MVOD_LK_PLAIN ? &plain : &vec;
	if (path == MVOD_LK_AVX2) {
#ifdef HAVE_AVX2
		static const struct kernels avx2 = {prep_avx2, mismatch_avx2};
		if (!__builtin_cpu_supports("avx2"))
			return -ENOTSUP;
		k = &avx2;
#else
		return -ENOTSUP;
#endif
	}
	struct tmpl T;
	for (int i = 0; i < n; i++)
		track(I, J, p, from + 2 * i, to + 2 * i, ok + i, k, &T);
	return 0;
}

void mvod_lk_flow(const struct mvod_lk_level *I, const struct mvod_lk_level *J,
		  const struct mvod_lk_params *p, const float *from, float *to, int n, uint8_t *ok)
{
	if (mvod_lk_flow_on(MVOD_LK_AVX2, I, J, p, from, to, n, ok))
		mvod_lk_flow_on(MVOD_LK_VECTOR, I, J, p, from, to, n, ok);
}

int mvod_lk_scharr_on(enum mvod_lk_path path, const uint8_t *img, ptrdiff_t stride, int w, int h,
		      int16_t *deriv, ptrdiff_t dstride, int16_t *tmp)
{
	int (*vertical)(const uint8_t *, const uint8_t *, const uint8_t *, int, int16_t *,
			int16_t *) = scharr_vertical_vec;
	int (*horizontal)(const int16_t *, const int16_t *, int, int16_t *) = scharr_horizontal_vec;
	if (path == MVOD_LK_AVX2) {
#ifdef HAVE_AVX2
		if (!__builtin_cpu_supports("avx2"))
			return -ENOTSUP;
		vertical = scharr_vertical_avx2;
		horizontal = scharr_horizontal_avx2;
#else
		return -ENOTSUP;
#endif
	}
	int16_t *t0 = tmp + 1, *t1 = tmp + w + 3;
	for (int y = 0; y < h; y++) {
		const uint8_t *s0 = img + (ptrdiff_t)reflect(y - 1, h) * stride;
		const uint8_t *s1 = img + (ptrdiff_t)y * stride;
		const uint8_t *s2 = img + (ptrdiff_t)reflect(y + 1, h) * stride;
		int16_t *d = deriv + (ptrdiff_t)y * dstride;
		int x = path == MVOD_LK_PLAIN ? 0 : vertical(s0, s1, s2, w, t0, t1);
		scharr_vertical_plain(s0, s1, s2, x, w, t0, t1);
		t0[-1] = t0[reflect(-1, w)];
		t0[w] = t0[reflect(w, w)];
		t1[-1] = t1[reflect(-1, w)];
		t1[w] = t1[reflect(w, w)];
		x = path == MVOD_LK_PLAIN ? 0 : horizontal(t0, t1, w, d);
		scharr_horizontal_plain(t0, t1, x, w, d);
	}
	return 0;
}

void mvod_lk_scharr(const uint8_t *img, ptrdiff_t stride, int w, int h, int16_t *deriv,
		    ptrdiff_t dstride, int16_t *tmp)
{
	if (mvod_lk_scharr_on(MVOD_LK_AVX2, img, stride, w, h, deriv, dstride, tmp))
		mvod_lk_scharr_on(MVOD_LK_VECTOR, img, stride, w, h, deriv, dstride, tmp);
}
