#include "match.h"

#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cv_shim.h"
#include "vo/core/hamming.h"

struct mvod_matcher {
	struct mvod_match_params p;
	int cap;
	float *best_a, *second_a; /* per feature of a: the two nearest distances in b */
	int *idx_a;               /* per feature of a: its nearest in b */
	int *best_b, *idx_b;      /* per feature of b: nearest Hamming distance in a, its index */
	uint64_t *words_a, *words_b; /* ORB descriptors as aligned 64-bit words */
	struct mvod_cv_nn *nn;    /* SIFT or FLANN: OpenCV finds the neighbours */
};

#define WORDS (MVOD_ORB_DESC_BYTES / 8)

static bool uses_flann(enum mvod_matcher_kind k)
{
	return k == MVOD_MATCHER_FLANN || k == MVOD_MATCHER_FLANN_RATIO;
}

static bool uses_cross_check(enum mvod_matcher_kind k)
{
	return k == MVOD_MATCHER_BF || k == MVOD_MATCHER_BF_CROSS;
}

/* mvod's own table serves ORB brute force; everything else goes through OpenCV. */
static bool own_table(const struct mvod_match_params *p)
{
	return p->detector == MVOD_DETECTOR_ORB && !uses_flann(p->kind);
}

int mvod_matcher_create(const struct mvod_match_params *p, int cap, struct mvod_matcher **out)
{
	if ((unsigned)p->kind >= MVOD_MATCHER_COUNT || p->best_n < 0)
		return -EINVAL;
	struct mvod_matcher *m = calloc(1, sizeof(*m));
	if (!m)
		return -ENOMEM;
	size_t n = (size_t)cap;
	m->p = *p;
	m->cap = cap;
	m->best_a = malloc(n * sizeof(float));
	m->second_a = malloc(n * sizeof(float));
	m->idx_a = malloc(n * sizeof(int));
	m->best_b = malloc(n * sizeof(int));
	m->idx_b = malloc(n * sizeof(int));
	int ret = -ENOMEM;
	if (!m->best_a || !m->second_a || !m->idx_a || !m->best_b || !m->idx_b)
		goto fail;
	if (own_table(p)) {
		m->words_a = malloc(n * WORDS * sizeof(uint64_t));
		m->words_b = malloc(n * WORDS * sizeof(uint64_t));
		if (!m->words_a || !m->words_b)
			goto fail;
	} else {
		ret = mvod_cv_nn_create(p->detector, uses_flann(p->kind), &m->nn);
		if (ret)
			goto fail;
	}
	*out = m;
	return 0;
fail:
	mvod_matcher_destroy(m);
	return ret;
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
	mvod_cv_nn_destroy(m->nn);
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
			int d = mvod_hamming_words(x, y);
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
		m->best_a[i] = (float)b1;
		m->second_a[i] = (float)b2;
		m->idx_a[i] = bi;
	}
}

/* Moves the k smallest distances of out[0..n) to its front (quickselect, in place). */
static void keep_closest(struct mvod_match *out, int n, int k)
{
	int lo = 0, hi = n - 1;
	while (lo < hi) {
		float pivot = out[(lo + hi) / 2].dist;
		int i = lo, j = hi;
		while (i <= j) {
			while (out[i].dist < pivot)
				i++;
			while (out[j].dist > pivot)
				j--;
			if (i <= j) {
				struct mvod_match t = out[i];
				out[i++] = out[j];
				out[j--] = t;
			}
		}
		if (k - 1 <= j)
			hi = j;
		else if (k - 1 >= i)
			lo = i;
		else
			return;
	}
}

static int neighbours(struct mvod_matcher *m, const struct mvod_features *a,
		      const struct mvod_features *b)
{
	int *idx_b = uses_cross_check(m->p.kind) ? m->idx_b : NULL;
	if (!own_table(&m->p))
		return mvod_cv_nn_search(m->nn, a, b, m->best_a, m->second_a, m->idx_a, idx_b);
	memcpy(m->words_a, a->desc, (size_t)a->n * MVOD_ORB_DESC_BYTES);
	memcpy(m->words_b, b->desc, (size_t)b->n * MVOD_ORB_DESC_BYTES);
	distance_table(m, a->n, b->n);
	return 0;
}

int mvod_match(struct mvod_matcher *m, const struct mvod_features *a,
	       const struct mvod_features *b, struct mvod_match *out, int cap, int *n_out)
{
	*n_out = 0;
	if (a->n > m->cap || b->n > m->cap || a->desc_bytes != mvod_cv_desc_bytes(m->p.detector) ||
	    b->desc_bytes != a->desc_bytes)
		return -EINVAL;
	if (a->n < 2 || b->n < 2)
		return 0;
	int ret = neighbours(m, a, b);
	if (ret)
		return ret;
	bool ratio = mvod_matcher_uses_ratio(m->p.kind) && m->p.ratio < 1.0;
	bool cross = uses_cross_check(m->p.kind);
	int n = 0;
	for (int i = 0; i < a->n && n < cap; i++) {
		int j = m->idx_a[i];
		if (j < 0 || (ratio && m->best_a[i] >= m->p.ratio * m->second_a[i]))
			continue;
		if (cross && m->idx_b[j] != i)
			continue;
		out[n++] = (struct mvod_match){.a = i, .b = j, .dist = m->best_a[i]};
	}
	if (m->p.kind == MVOD_MATCHER_BF_CROSS && m->p.best_n && n > m->p.best_n) {
		keep_closest(out, n, m->p.best_n);
		n = m->p.best_n;
	}
	*n_out = n;
	return 0;
}
