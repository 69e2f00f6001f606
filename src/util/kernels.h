#ifndef MVOD_UTIL_KERNELS_H
#define MVOD_UTIL_KERNELS_H

/*
 * Small integer pixel kernels of the hot loop, each with an SSE2 path (x86-64), a NEON path
 * (arm64) and the plain C it must equal exactly: the vector paths compute the same integers in
 * another order, so results (and trajectories) do not depend on the machine's SIMD. The plain
 * forms are exported so that tests/unit/test_kernels.c compares them, on x86-64 in make test and
 * on arm64 under qemu in make cross-arm64.
 */
#include <stdint.h>

/*
 * Harris corner score (k = 0.04) over the 7x7 window around the pixel p points at, with central
 * differences. Reads bytes -4 .. 5 of rows -3 .. 3 and -3 .. 4 of rows -4 and 4 around p (the
 * vector paths read byte 5, one right of the differences, and mask it).
 */
float mvod_harris7(const uint8_t *p, int stride);
float mvod_harris7_plain(const uint8_t *p, int stride);

/* PNG's Sub filter for 1 byte a pixel: d[x] = s[x] + d[x - 1] modulo 256, d[-1] = 0. */
void mvod_png_sub(uint8_t *d, const uint8_t *s, int w);
void mvod_png_sub_plain(uint8_t *d, const uint8_t *s, int w);

#endif
