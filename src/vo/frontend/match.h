/*
 * Pairing features of two frames: nearest neighbours (mvod's own brute-force Hamming table for
 * ORB, OpenCV for SIFT and for FLANN), then the matcher kind's filters: Lowe's ratio test, the
 * mutual cross-check, the best_n closest.
 */
#ifndef MVOD_MATCH_H
#define MVOD_MATCH_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "mvod/vo.h"
#include "vo/core/types.h"

struct mvod_match_params {
	enum mvod_matcher_kind kind;
	enum mvod_detector detector; /* decides the descriptor type and distance */
	double ratio;                /* ratio test threshold for kinds with one; >= 1 = off */
	int best_n;                  /* BF_CROSS: matches kept, the closest first; 0 = all */
};

/*
 * Hamming distance in bits of two ORB descriptors held as 4 aligned 64-bit words each: the
 * inner loop of the distance table. Taking words, not bytes, matters: with a memcpy from bytes
 * in this loop gcc 12 emitted 44 % more instructions per pair (callgrind, KITTI 06: the table
 * went 1.90e9 -> 2.74e9 instructions over 20 frames).
 */
static inline int mvod_hamming_words(const uint64_t *x, const uint64_t *y)
{
	return __builtin_popcountll(x[0] ^ y[0]) + __builtin_popcountll(x[1] ^ y[1]) +
	       __builtin_popcountll(x[2] ^ y[2]) + __builtin_popcountll(x[3] ^ y[3]);
}

/*
 * The same for two descriptors of MVOD_ORB_DESC_BYTES = 32 bytes at any alignment (matching by
 * projection, project_match.c): memcpy compiles to plain loads.
 */
static inline int mvod_hamming256(const uint8_t *a, const uint8_t *b)
{
	uint64_t x[4], y[4];
	memcpy(x, a, sizeof(x));
	memcpy(y, b, sizeof(y));
	return mvod_hamming_words(x, y);
}

struct mvod_matcher;

/* Tables for up to cap features on each side, allocated once. */
int mvod_matcher_create(const struct mvod_match_params *p, int cap, struct mvod_matcher **out);
void mvod_matcher_destroy(struct mvod_matcher *m);

/*
 * Matches a to b: a's nearest neighbour in b, kept when it passes the kind's filters (ratio
 * test: best < ratio * second best; cross-check: a is also b's nearest neighbour in a). Writes
 * at most cap matches; -EINVAL when a set exceeds the tables.
 */
int mvod_match(struct mvod_matcher *m, const struct mvod_features *a,
	       const struct mvod_features *b, struct mvod_match *out, int cap, int *n_out);

#endif
