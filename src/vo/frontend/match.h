/*
 * Pairing features of two frames: nearest neighbours (mvod's own brute-force Hamming table for
 * ORB, OpenCV for SIFT and for FLANN), then the matcher kind's filters: Lowe's ratio test, the
 * mutual cross-check, the best_n closest.
 */
#ifndef MVOD_MATCH_H
#define MVOD_MATCH_H

#include <stdbool.h>
#include <stdint.h>

#include "mvod/vo_types.h"
#include "vo/core/types.h"

struct mvod_match_params {
	enum mvod_matcher_kind kind;
	enum mvod_detector detector; /* decides the descriptor type and distance */
	double ratio;                /* ratio test threshold for kinds with one; >= 1 = off */
	int best_n;                  /* BF_CROSS: matches kept, the closest first; 0 = all */
};


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
