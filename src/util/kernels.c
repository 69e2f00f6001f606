#include "util/kernels.h"

#include <stddef.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__ARM_NEON) && defined(__aarch64__)
#include <arm_neon.h>
#endif

/*
 * The score from the window's integer sums, shared by every path so that only the sums could
 * differ (and they do not: they are exact integers, each term at most 255^2, 49 of them under
 * 2^24, so converting them to float is exact too).
 */
static float harris_score(int32_t a, int32_t b, int32_t c)
{
	float fa = (float)a, fb = (float)b, fc = (float)c;
	return fa * fb - fc * fc - 0.04f * (fa + fb) * (fa + fb);
}

/*
 * Summing the products as int rather than float gave the same scores at 73 % of the
 * instructions (callgrind, KITTI 06, 20 frames: 93.3e6 -> 68.2e6 in harris()).
 */
float mvod_harris7_plain(const uint8_t *p, int stride)
{
	int32_t a = 0, b = 0, c = 0;
	for (int dy = -3; dy <= 3; dy++) {
		const uint8_t *r = p + (ptrdiff_t)dy * stride;
		for (int dx = -3; dx <= 3; dx++) {
			int32_t ix = r[dx + 1] - r[dx - 1];
			int32_t iy = r[dx + stride] - r[dx - stride];
			a += ix * ix;
			b += iy * iy;
			c += ix * iy;
		}
	}
	return harris_score(a, b, c);
}

/*
 * Vectors: a row's seven differences are one vector of int16 (|d| <= 255; lane 7, outside the
 * window, zeroed) whose products are summed into int32 lanes: the same integers in another
 * order. SSE2's pmaddwd: 3.1e6 -> 0.9e6 instructions per KITTI frame, trajectories
 * byte-identical (GCC's generic 8 x int32 vectors were slower: SSE2 has no 32-bit multiply).
 * NEON's widening multiply-accumulate does the same on arm64.
 */
#if defined(__SSE2__)
float mvod_harris7(const uint8_t *p, int stride)
{
	const __m128i keep = _mm_set_epi16(0, -1, -1, -1, -1, -1, -1, -1), z = _mm_setzero_si128();
	__m128i a = z, b = z, c = z;
	for (int dy = -3; dy <= 3; dy++) {
		const uint8_t *r = p + (ptrdiff_t)dy * stride;
		/* Bytes -4 .. 3 and -2 .. 5 of the row (lane j: x = j - 3 after the difference). */
		__m128i l = _mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)(r - 4)), z);
		__m128i rr = _mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)(r - 2)), z);
		__m128i u = _mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)(r - 3 - stride)), z);
		__m128i d = _mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)(r - 3 + stride)), z);
		__m128i ix = _mm_and_si128(_mm_sub_epi16(rr, l), keep);
		__m128i iy = _mm_and_si128(_mm_sub_epi16(d, u), keep);
		a = _mm_add_epi32(a, _mm_madd_epi16(ix, ix));
		b = _mm_add_epi32(b, _mm_madd_epi16(iy, iy));
		c = _mm_add_epi32(c, _mm_madd_epi16(ix, iy));
	}
	int32_t sa[4], sb[4], sc[4];
	_mm_storeu_si128((__m128i *)sa, a);
	_mm_storeu_si128((__m128i *)sb, b);
	_mm_storeu_si128((__m128i *)sc, c);
	return harris_score(sa[0] + sa[1] + sa[2] + sa[3], sb[0] + sb[1] + sb[2] + sb[3],
			    sc[0] + sc[1] + sc[2] + sc[3]);
}
#elif defined(__ARM_NEON) && defined(__aarch64__)
float mvod_harris7(const uint8_t *p, int stride)
{
	static const int16_t lanes[8] = {-1, -1, -1, -1, -1, -1, -1, 0};
	const int16x8_t keep = vld1q_s16(lanes);
	int32x4_t a = vdupq_n_s32(0), b = a, c = a;
	for (int dy = -3; dy <= 3; dy++) {
		const uint8_t *r = p + (ptrdiff_t)dy * stride;
		int16x8_t l = vreinterpretq_s16_u16(vmovl_u8(vld1_u8(r - 4)));
		int16x8_t rr = vreinterpretq_s16_u16(vmovl_u8(vld1_u8(r - 2)));
		int16x8_t u = vreinterpretq_s16_u16(vmovl_u8(vld1_u8(r - 3 - stride)));
		int16x8_t d = vreinterpretq_s16_u16(vmovl_u8(vld1_u8(r - 3 + stride)));
		int16x8_t ix = vandq_s16(vsubq_s16(rr, l), keep);
		int16x8_t iy = vandq_s16(vsubq_s16(d, u), keep);
		a = vmlal_high_s16(vmlal_s16(a, vget_low_s16(ix), vget_low_s16(ix)), ix, ix);
		b = vmlal_high_s16(vmlal_s16(b, vget_low_s16(iy), vget_low_s16(iy)), iy, iy);
		c = vmlal_high_s16(vmlal_s16(c, vget_low_s16(ix), vget_low_s16(iy)), ix, iy);
	}
	return harris_score(vaddvq_s32(a), vaddvq_s32(b), vaddvq_s32(c));
}
#else
float mvod_harris7(const uint8_t *p, int stride)
{
	return mvod_harris7_plain(p, stride);
}
#endif

/* Bytes x .. w - 1 of the row, after the first x. */
static void sub_from(uint8_t *d, const uint8_t *s, int x, int w)
{
	uint8_t left = x ? d[x - 1] : 0;
	for (; x < w; x++)
		d[x] = left = (uint8_t)(s[x] + left);
}

void mvod_png_sub_plain(uint8_t *d, const uint8_t *s, int w)
{
	sub_from(d, s, 0, w);
}

/*
 * KITTI's PNGs use Sub on every row. Vectors: 16 bytes at a time as a prefix sum in four shifted
 * adds plus the last byte before them, the same sums modulo 256 (SSE2: mvod_png_grey_decode
 * 2.15e6 -> 0.71e6 instructions per 1226x370 frame, callgrind, KITTI 06/07 trajectories
 * byte-identical); the remainder in plain C.
 */
void mvod_png_sub(uint8_t *d, const uint8_t *s, int w)
{
	int x = 0;
#if defined(__SSE2__)
	__m128i carry = _mm_setzero_si128(); /* every byte: d[x - 1] */
	for (; x + 16 <= w; x += 16) {
		__m128i v = _mm_loadu_si128((const __m128i *)(s + x));
		v = _mm_add_epi8(v, _mm_slli_si128(v, 1));
		v = _mm_add_epi8(v, _mm_slli_si128(v, 2));
		v = _mm_add_epi8(v, _mm_slli_si128(v, 4));
		v = _mm_add_epi8(v, _mm_slli_si128(v, 8));
		v = _mm_add_epi8(v, carry);
		_mm_storeu_si128((__m128i *)(d + x), v);
		carry = _mm_shuffle_epi32(_mm_shufflehi_epi16(_mm_srli_epi16(v, 8), 0xff), 0xff);
		carry = _mm_or_si128(carry, _mm_slli_epi16(carry, 8));
	}
#elif defined(__ARM_NEON) && defined(__aarch64__)
	const uint8x16_t z = vdupq_n_u8(0);
	uint8x16_t carry = z; /* every byte: d[x - 1] */
	for (; x + 16 <= w; x += 16) {
		uint8x16_t v = vld1q_u8(s + x);
		/* vextq_u8(z, v, 16 - n): lane i holds v[i - n], zero below n. */
		v = vaddq_u8(v, vextq_u8(z, v, 15));
		v = vaddq_u8(v, vextq_u8(z, v, 14));
		v = vaddq_u8(v, vextq_u8(z, v, 12));
		v = vaddq_u8(v, vextq_u8(z, v, 8));
		v = vaddq_u8(v, carry);
		vst1q_u8(d + x, v);
		carry = vdupq_laneq_u8(v, 15);
	}
#endif
	sub_from(d, s, x, w);
}
