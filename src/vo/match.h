/*
 * Brute-force Hamming matching of binary descriptors with Lowe's ratio test and a mutual
 * cross-check, in one pass over the distance table (each distance computed once).
 */
#ifndef MVOD_MATCH_H
#define MVOD_MATCH_H

#include <stdbool.h>

#include "cv_shim.h"

struct mvod_matcher;

/* Tables for up to cap features on each side, allocated once. */
int mvod_matcher_create(int cap, struct mvod_matcher **out);
void mvod_matcher_destroy(struct mvod_matcher *m);

/*
 * Matches a to b: a's nearest neighbour in b, kept when it passes the ratio test (best <
 * ratio * second best; ratio >= 1 disables it) and, with cross_check, when it is also b's
 * nearest neighbour in a. Writes at most cap matches; -EINVAL when a set exceeds the tables.
 */
int mvod_match(struct mvod_matcher *m, const struct mvod_features *a,
	       const struct mvod_features *b, double ratio, bool cross_check,
	       struct mvod_match *out, int cap, int *n_out);

#endif
