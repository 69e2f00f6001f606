#include "match.h"

#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct mvod_matcher {
	int cap;
	int *best_a, *second_a, *idx_a; /* per feature of a: two nearest distances in b, best index */
	int *best_b, *idx_b;            /* per feature of b: nearest distance in a, its index */
	uint64_t *words_a, *words_b;    /* descriptors as aligned 64-bit words */
};

#define WORDS (MVOD_ORB_DESC_BYTES / 8)

int mvod_matcher_create(int cap, struct mvod_matcher **out)
{
	struct mvod_matcher *m = calloc(1, sizeof(*m));
	if (!m)
		return -ENOMEM;
	size_t n = (size_t)cap;
	m->cap = cap;
	m->best_a = malloc(n * sizeof(int));
	m->second_a = malloc(n * sizeof(int));
	m->idx_a = malloc(n * sizeof(int));
	m->best_b = malloc(n * sizeof(int));
	m->idx_b = malloc(n * sizeof(int));
	m->words_a = malloc(n * WORDS * sizeof(uint64_t));
	m->words_b = malloc(n * WORDS * sizeof(uint64_t));
	if (!m->best_a || !m->second_a || !m->idx_a || !m->best_b || !m->idx_b || !m->words_a ||
	    !m->words_b) {
		mvod_matcher_destroy(m);
		return -ENOMEM;
	}
	*out = m;
	return 0;
}

void mvod_matcher_destroy(struct mvod_matcher *m)
{
	if (!m)
		return;
	free(m->best_a);
	free(m->second_a);
	free(m->idx_a);
	free(m->best_b);
	free(m->idx_b);
	free(m->words_a);
	free(m->words_b);
	free(m);
}

/*
 * The distance table is the hot loop of the frontend. On x86-64 a popcnt clone is chosen at
 * load time (baseline x86-64 lacks the instruction); elsewhere the compiler's popcount is
 * already the native one (NEON cnt on the Raspberry Pi).
 */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HOT_CLONES __attribute__((target_clones("popcnt", "default")))
#else
#define HOT_CLONES
#endif

HOT_CLONES
static void distance_table(struct mvod_matcher *m, int na, int nb)
{
	for (int j = 0; j < nb; j++) {
		m->best_b[j] = INT_MAX;
		m->idx_b[j] = -1;
	}
	for (int i = 0; i < na; i++) {
		const uint64_t *x = m->words_a + (size_t)i * WORDS;
		int b1 = INT_MAX, b2 = INT_MAX, bi = -1;
		for (int j = 0; j < nb; j++) {
			const uint64_t *y = m->words_b + (size_t)j * WORDS;
			int d = __builtin_popcountll(x[0] ^ y[0]) + __builtin_popcountll(x[1] ^ y[1]) +
				__builtin_popcountll(x[2] ^ y[2]) + __builtin_popcountll(x[3] ^ y[3]);
			if (d < b1) {
				b2 = b1;
				b1 = d;
				bi = j;
			} else if (d < b2) {
				b2 = d;
			}
			if (d < m->best_b[j]) {
				m->best_b[j] = d;
				m->idx_b[j] = i;
			}
		}
		m->best_a[i] = b1;
		m->second_a[i] = b2;
		m->idx_a[i] = bi;
	}
}

int mvod_match(struct mvod_matcher *m, const struct mvod_features *a,
	       const struct mvod_features *b, double ratio, bool cross_check,
	       struct mvod_match *out, int cap, int *n_out)
{
	*n_out = 0;
	if (a->n > m->cap || b->n > m->cap)
		return -EINVAL;
	if (a->n < 2 || b->n < 2)
		return 0;
	memcpy(m->words_a, a->desc, (size_t)a->n * MVOD_ORB_DESC_BYTES);
	memcpy(m->words_b, b->desc, (size_t)b->n * MVOD_ORB_DESC_BYTES);
	distance_table(m, a->n, b->n);
	int n = 0;
	for (int i = 0; i < a->n && n < cap; i++) {
		int j = m->idx_a[i];
		if (ratio < 1.0 && m->best_a[i] >= ratio * m->second_a[i])
			continue;
		if (cross_check && m->idx_b[j] != i)
			continue;
		out[n].a = i;
		out[n].b = j;
		n++;
	}
	*n_out = n;
	return 0;
}
