#include "map.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/geom.h"
#include "vo/core/hamming.h"

struct mvod_map {
	struct mvod_map_params p;
	struct mvod_map_keyframe *kf; /* [kf_cap] ring slots; id 0 = empty */
	uint32_t *kf_gen;             /* [kf_cap] generation the slot's next keyframe gets */
	int kf_head, kf_n;            /* oldest slot, keyframes in the ring */
	uint64_t kf_seq;              /* seq of the next keyframe */
	struct mvod_map_kp *kp_pool;  /* [kf_cap * kp_cap] */
	uint8_t *desc_pool;           /* [kf_cap * kp_cap * 32] */
	mvod_map_id *ptid_pool;       /* [kf_cap * kp_cap] */
	struct mvod_map_point *pt;    /* [point_cap]; id 0 = free */
	struct mvod_map_obs *obs_pool; /* [point_cap * kf_cap] */
	uint32_t *pt_gen;             /* [point_cap] */
	int *free_slots;              /* [point_cap] stack of free point slots */
	int n_free;
	uint8_t *mark;                /* [point_cap] scratch of mvod_map_check */
	int *dist;                    /* [kf_cap * kf_cap] scratch of mvod_map_update_desc */
};

void mvod_map_params_default(struct mvod_map_params *p)
{
	*p = (struct mvod_map_params){
		.kf_cap = 7,
		.kp_cap = 2000,
		.point_cap = 20000,
		.min_found_ratio = 0.25,
		.min_obs = 3,
		.min_obs_keep = 2,
	};
}

static mvod_map_id make_id(uint32_t gen, int slot)
{
	return ((uint64_t)gen << 32) | (uint32_t)slot;
}

static int slot_of(mvod_map_id id, int cap)
{
	uint64_t s = id & 0xffffffffu;
	return id != MVOD_MAP_NONE && s < (uint64_t)cap ? (int)s : -1;
}

/* Next generation of a slot; never 0, so no id is ever MVOD_MAP_NONE. */
static uint32_t next_gen(uint32_t g)
{
	return g == UINT32_MAX ? 1 : g + 1;
}

static bool params_ok(const struct mvod_map_params *p)
{
	/* Bounds keep every pool size within size_t and slot numbers within 32 bits. */
	return p->kf_cap >= 2 && p->kf_cap <= 256 && p->kp_cap >= 1 && p->kp_cap <= (1 << 20) &&
	       p->point_cap >= 1 && p->point_cap <= (1 << 24) && p->min_found_ratio >= 0 &&
	       p->min_found_ratio <= 1 && p->min_obs >= 1 && p->min_obs_keep >= 0;
}

static void wire_slots(struct mvod_map *m)
{
	size_t kp = (size_t)m->p.kp_cap;
	for (int s = 0; s < m->p.kf_cap; s++) {
		m->kf[s].kp = m->kp_pool + s * kp;
		m->kf[s].desc = m->desc_pool + s * kp * MVOD_MAP_DESC_BYTES;
		m->kf[s].pt = m->ptid_pool + s * kp;
		m->kf_gen[s] = 1;
	}
	for (int s = 0; s < m->p.point_cap; s++) {
		m->pt[s].obs = m->obs_pool + (size_t)s * m->p.kf_cap;
		m->pt_gen[s] = 1;
		m->free_slots[s] = m->p.point_cap - 1 - s; /* slot 0 is handed out first */
	}
	m->n_free = m->p.point_cap;
}

int mvod_map_create(struct mvod_map **out, const struct mvod_map_params *p)
{
	*out = NULL;
	if (!params_ok(p))
		return -EINVAL;
	struct mvod_map *m = calloc(1, sizeof(*m));
	if (!m)
		return -ENOMEM;
	m->p = *p;
	size_t nkp = (size_t)p->kf_cap * p->kp_cap, npt = (size_t)p->point_cap;
	m->kf = calloc((size_t)p->kf_cap, sizeof(*m->kf));
	m->kf_gen = calloc((size_t)p->kf_cap, sizeof(*m->kf_gen));
	m->kp_pool = calloc(nkp, sizeof(*m->kp_pool));
	m->desc_pool = calloc(nkp, MVOD_MAP_DESC_BYTES);
	m->ptid_pool = calloc(nkp, sizeof(*m->ptid_pool));
	m->pt = calloc(npt, sizeof(*m->pt));
	m->obs_pool = calloc(npt * p->kf_cap, sizeof(*m->obs_pool));
	m->pt_gen = calloc(npt, sizeof(*m->pt_gen));
	m->free_slots = calloc(npt, sizeof(*m->free_slots));
	m->mark = calloc(npt, 1);
	m->dist = calloc((size_t)p->kf_cap * p->kf_cap, sizeof(*m->dist));
	if (!m->kf || !m->kf_gen || !m->kp_pool || !m->desc_pool || !m->ptid_pool || !m->pt ||
	    !m->obs_pool || !m->pt_gen || !m->free_slots || !m->mark || !m->dist) {
		mvod_map_destroy(m);
		return -ENOMEM;
	}
	wire_slots(m);
	*out = m;
	return 0;
}

void mvod_map_destroy(struct mvod_map *m)
{
	if (!m)
		return;
	free(m->kf);
	free(m->kf_gen);
	free(m->kp_pool);
	free(m->desc_pool);
	free(m->ptid_pool);
	free(m->pt);
	free(m->obs_pool);
	free(m->pt_gen);
	free(m->free_slots);
	free(m->mark);
	free(m->dist);
	free(m);
}

static struct mvod_map_keyframe *kf_get(const struct mvod_map *m, mvod_map_id id)
{
	int s = slot_of(id, m->p.kf_cap);
	return s >= 0 && m->kf[s].id == id ? &m->kf[s] : NULL;
}

static struct mvod_map_point *pt_get(const struct mvod_map *m, mvod_map_id id)
{
	int s = slot_of(id, m->p.point_cap);
	return s >= 0 && m->pt[s].id == id ? &m->pt[s] : NULL;
}

const struct mvod_map_keyframe *mvod_map_keyframe(const struct mvod_map *m, mvod_map_id id)
{
	return kf_get(m, id);
}

const struct mvod_map_point *mvod_map_point(const struct mvod_map *m, mvod_map_id id)
{
	return pt_get(m, id);
}

/* Index of kf among pt's observations, or -1. */
static int obs_index(const struct mvod_map_point *pt, mvod_map_id kf)
{
	for (int i = 0; i < pt->n_obs; i++)
		if (pt->obs[i].kf == kf)
			return i;
	return -1;
}

/* Drops observation i of pt on both sides (the keyframe, when live, frees its keypoint). */
static void obs_drop(struct mvod_map *m, struct mvod_map_point *pt, int i)
{
	struct mvod_map_keyframe *k = kf_get(m, pt->obs[i].kf);
	if (k)
		k->pt[pt->obs[i].kp] = MVOD_MAP_NONE;
	pt->obs[i] = pt->obs[--pt->n_obs];
}

static void point_free(struct mvod_map *m, struct mvod_map_point *pt)
{
	while (pt->n_obs > 0)
		obs_drop(m, pt, pt->n_obs - 1);
	int s = (int)(pt - m->pt);
	pt->id = MVOD_MAP_NONE;
	m->pt_gen[s] = next_gen(m->pt_gen[s]);
	m->free_slots[m->n_free++] = s;
}

/* The oldest keyframe leaves: its observations leave their points; weak points are erased. */
static void evict_oldest(struct mvod_map *m, struct mvod_map_stats *st)
{
	struct mvod_map_keyframe *k = &m->kf[m->kf_head];
	for (int j = 0; j < k->n; j++) {
		struct mvod_map_point *pt = pt_get(m, k->pt[j]);
		if (!pt)
			continue;
		obs_drop(m, pt, obs_index(pt, k->id));
		if (pt->n_obs < m->p.min_obs_keep) {
			point_free(m, pt);
			st->erased_points++;
		}
	}
	k->id = MVOD_MAP_NONE;
	m->kf_head = (m->kf_head + 1) % m->p.kf_cap;
	m->kf_n--;
	st->evicted_kf++;
}

void mvod_map_reset(struct mvod_map *m)
{
	struct mvod_map_stats st = {0};
	while (m->kf_n > 0)
		evict_oldest(m, &st);
	for (int s = 0; s < m->p.point_cap; s++)
		if (m->pt[s].id != MVOD_MAP_NONE)
			point_free(m, &m->pt[s]);
}

int mvod_map_add_keyframe(struct mvod_map *m, const struct mvod_map_kf_in *in, mvod_map_id *out,
			  struct mvod_map_stats *st)
{
	struct mvod_map_stats ignored;
	if (!st)
		st = &ignored;
	*st = (struct mvod_map_stats){0};
	if (in->n < 0 || in->n > m->p.kp_cap)
		return -EINVAL;
	if (m->kf_n == m->p.kf_cap)
		evict_oldest(m, st);
	int s = (m->kf_head + m->kf_n) % m->p.kf_cap;
	struct mvod_map_keyframe *k = &m->kf[s];
	k->id = make_id(m->kf_gen[s], s);
	m->kf_gen[s] = next_gen(m->kf_gen[s]);
	k->seq = m->kf_seq++;
	k->utime = in->utime;
	memcpy(k->Rcw, in->Rcw, sizeof(k->Rcw));
	memcpy(k->tcw, in->tcw, sizeof(k->tcw));
	k->n = in->n;
	if (in->n > 0) { /* a keyframe without keypoints may pass NULL arrays */
		memcpy(k->kp, in->kp, (size_t)in->n * sizeof(*k->kp));
		memcpy(k->desc, in->desc, (size_t)in->n * MVOD_MAP_DESC_BYTES);
	}
	for (int j = 0; j < in->n; j++)
		k->pt[j] = MVOD_MAP_NONE;
	m->kf_n++;
	*out = k->id;
	return 0;
}

int mvod_map_set_pose(struct mvod_map *m, mvod_map_id kf, const double Rcw[9],
		      const double tcw[3])
{
	struct mvod_map_keyframe *k = kf_get(m, kf);
	if (!k)
		return -ENOENT;
	memcpy(k->Rcw, Rcw, sizeof(k->Rcw));
	memcpy(k->tcw, tcw, sizeof(k->tcw));
	return 0;
}

int mvod_map_rescale(struct mvod_map *m, const double centre[3], double s)
{
	if (!(s > 0 && isfinite(s)))
		return -EINVAL;
	for (int i = 0; i < m->kf_n; i++) {
		struct mvod_map_keyframe *k = &m->kf[(m->kf_head + i) % m->p.kf_cap];
		mvod_rigid_scale(k->Rcw, k->tcw, centre, s);
	}
	for (int i = 0; i < m->p.point_cap; i++)
		for (int k = 0; k < 3 && m->pt[i].id != MVOD_MAP_NONE; k++)
			m->pt[i].pos[k] = centre[k] + s * (m->pt[i].pos[k] - centre[k]);
	return 0;
}

int mvod_map_keyframes(const struct mvod_map *m, mvod_map_id *ids, int cap)
{
	int n = 0;
	for (int i = 0; i < m->kf_n && n < cap; i++)
		ids[n++] = m->kf[(m->kf_head + i) % m->p.kf_cap].id;
	return n;
}

int mvod_map_n_keyframes(const struct mvod_map *m)
{
	return m->kf_n;
}

int mvod_map_add_point(struct mvod_map *m, const double pos[3],
		       const uint8_t desc[MVOD_MAP_DESC_BYTES], mvod_map_id kf, mvod_map_id *out)
{
	const struct mvod_map_keyframe *k = kf_get(m, kf);
	if (!k)
		return -ENOENT;
	if (m->n_free == 0)
		return -ENOSPC;
	int s = m->free_slots[--m->n_free];
	struct mvod_map_point *pt = &m->pt[s];
	pt->id = make_id(m->pt_gen[s], s);
	memcpy(pt->pos, pos, sizeof(pt->pos));
	memcpy(pt->desc, desc, MVOD_MAP_DESC_BYTES);
	pt->created_by = kf;
	pt->created_seq = k->seq;
	pt->visible = pt->found = 0;
	pt->n_obs = 0;
	*out = pt->id;
	return 0;
}

int mvod_map_set_point(struct mvod_map *m, mvod_map_id id, const double pos[3])
{
	struct mvod_map_point *pt = pt_get(m, id);
	if (!pt)
		return -ENOENT;
	memcpy(pt->pos, pos, sizeof(pt->pos));
	return 0;
}

static const uint8_t *obs_desc(const struct mvod_map *m, const struct mvod_map_obs *o)
{
	return kf_get(m, o->kf)->desc + (size_t)o->kp * MVOD_MAP_DESC_BYTES;
}

/* Median of row i of the n x n distance table (n <= kf_cap: a partial selection sort). */
static int row_median(int *row, int n)
{
	for (int a = 0; a <= n / 2; a++)
		for (int b = a + 1; b < n; b++)
			if (row[b] < row[a]) {
				int x = row[a];
				row[a] = row[b];
				row[b] = x;
			}
	return row[n / 2];
}

int mvod_map_update_desc(struct mvod_map *m, mvod_map_id id)
{
	struct mvod_map_point *pt = pt_get(m, id);
	if (!pt)
		return -ENOENT;
	int n = pt->n_obs, best = -1, best_med = 0;
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++)
			m->dist[i * n + j] = mvod_hamming256(obs_desc(m, &pt->obs[i]),
							     obs_desc(m, &pt->obs[j]));
	for (int i = 0; i < n; i++) {
		int med = row_median(m->dist + i * n, n);
		if (best < 0 || med < best_med) {
			best = i;
			best_med = med;
		}
	}
	if (best >= 0)
		memcpy(pt->desc, obs_desc(m, &pt->obs[best]), MVOD_MAP_DESC_BYTES);
	return 0;
}

/* Adds without wrapping: counters saturate rather than make a point look new. */
static uint32_t sat_add(uint32_t a, uint64_t n)
{
	uint64_t s = (uint64_t)a + n;
	return s > UINT32_MAX ? UINT32_MAX : (uint32_t)s;
}

int mvod_map_count(struct mvod_map *m, mvod_map_id id, int n_visible, int n_found)
{
	struct mvod_map_point *pt = pt_get(m, id);
	if (!pt)
		return -ENOENT;
	pt->visible = sat_add(pt->visible, n_visible > 0 ? (uint64_t)n_visible : 0);
	pt->found = sat_add(pt->found, n_found > 0 ? (uint64_t)n_found : 0);
	return 0;
}

int mvod_map_erase_point(struct mvod_map *m, mvod_map_id id)
{
	struct mvod_map_point *pt = pt_get(m, id);
	if (!pt)
		return -ENOENT;
	point_free(m, pt);
	return 0;
}

int mvod_map_points(const struct mvod_map *m, mvod_map_id *ids, int cap)
{
	int n = 0;
	for (int s = 0; s < m->p.point_cap && n < cap; s++)
		if (m->pt[s].id != MVOD_MAP_NONE)
			ids[n++] = m->pt[s].id;
	return n;
}

int mvod_map_n_points(const struct mvod_map *m)
{
	return m->p.point_cap - m->n_free;
}

int mvod_map_add_obs(struct mvod_map *m, mvod_map_id id, mvod_map_id kf, int kp)
{
	struct mvod_map_point *pt = pt_get(m, id);
	struct mvod_map_keyframe *k = kf_get(m, kf);
	if (!pt || !k)
		return -ENOENT;
	if (kp < 0 || kp >= k->n)
		return -EINVAL;
	if (k->pt[kp] != MVOD_MAP_NONE || obs_index(pt, kf) >= 0)
		return -EEXIST;
	/* n_obs < kf_cap holds here: one observation per live keyframe, all in the ring. */
	pt->obs[pt->n_obs++] = (struct mvod_map_obs){kf, kp};
	k->pt[kp] = id;
	return 0;
}

int mvod_map_remove_obs(struct mvod_map *m, mvod_map_id id, mvod_map_id kf)
{
	struct mvod_map_point *pt = pt_get(m, id);
	int i = pt ? obs_index(pt, kf) : -1;
	if (i < 0)
		return -ENOENT;
	obs_drop(m, pt, i);
	return 0;
}

int mvod_map_fuse(struct mvod_map *m, mvod_map_id keep, mvod_map_id drop)
{
	struct mvod_map_point *a = pt_get(m, keep), *b = pt_get(m, drop);
	if (!a || !b)
		return -ENOENT;
	if (a == b)
		return -EINVAL;
	while (b->n_obs > 0) {
		struct mvod_map_obs o = b->obs[b->n_obs - 1];
		struct mvod_map_keyframe *k = kf_get(m, o.kf);
		obs_drop(m, b, b->n_obs - 1); /* frees the keypoint */
		if (k && obs_index(a, o.kf) < 0) {
			a->obs[a->n_obs++] = o;
			k->pt[o.kp] = keep;
		}
	}
	a->visible = sat_add(a->visible, b->visible);
	a->found = sat_add(a->found, b->found);
	point_free(m, b);
	return 0;
}

/* The rules of mvod_map_params, for a point of a map whose newest keyframe has seq newest. */
static bool cull_rule(const struct mvod_map_params *p, const struct mvod_map_point *pt,
		      uint64_t newest)
{
	uint64_t age = newest - pt->created_seq;
	if (age >= 3)
		return false; /* out of probation: only eviction removes it */
	/* visible == 0: never predicted in view yet, no evidence against it. */
	if (pt->visible > 0 && (double)pt->found < p->min_found_ratio * pt->visible)
		return true;
	return age >= 2 && pt->n_obs < p->min_obs;
}

int mvod_map_cull(struct mvod_map *m, struct mvod_map_stats *st)
{
	struct mvod_map_stats ignored;
	if (!st)
		st = &ignored;
	*st = (struct mvod_map_stats){0};
	if (m->kf_seq == 0)
		return 0;
	for (int s = 0; s < m->p.point_cap; s++) {
		struct mvod_map_point *pt = &m->pt[s];
		if (pt->id != MVOD_MAP_NONE && cull_rule(&m->p, pt, m->kf_seq - 1)) {
			point_free(m, pt);
			st->erased_points++;
		}
	}
	return 0;
}

/* One point's side of the invariants. */
static bool point_ok(const struct mvod_map *m, const struct mvod_map_point *pt)
{
	if (slot_of(pt->id, m->p.point_cap) != (int)(pt - m->pt) || pt->n_obs < 0 ||
	    pt->n_obs > m->p.kf_cap)
		return false;
	for (int i = 0; i < pt->n_obs; i++) {
		const struct mvod_map_keyframe *k = kf_get(m, pt->obs[i].kf);
		int kp = pt->obs[i].kp;
		if (!k || kp < 0 || kp >= k->n || k->pt[kp] != pt->id)
			return false;
		for (int j = 0; j < i; j++)
			if (pt->obs[j].kf == pt->obs[i].kf)
				return false;
	}
	return true;
}

/* One keyframe's side: every keypoint naming a point is in that point's list. */
static bool keyframe_ok(const struct mvod_map *m, const struct mvod_map_keyframe *k)
{
	if (k->n < 0 || k->n > m->p.kp_cap)
		return false;
	for (int j = 0; j < k->n; j++) {
		if (k->pt[j] == MVOD_MAP_NONE)
			continue;
		const struct mvod_map_point *pt = pt_get(m, k->pt[j]);
		int i = pt ? obs_index(pt, k->id) : -1;
		if (i < 0 || pt->obs[i].kp != j)
			return false;
	}
	return true;
}

int mvod_map_check(const struct mvod_map *m)
{
	int live = 0;
	for (int i = 0; i < m->kf_n; i++) {
		const struct mvod_map_keyframe *k = &m->kf[(m->kf_head + i) % m->p.kf_cap];
		if (k->id == MVOD_MAP_NONE || !keyframe_ok(m, k))
			return -EUCLEAN;
	}
	for (int s = 0; s < m->p.kf_cap; s++)
		live += m->kf[s].id != MVOD_MAP_NONE;
	if (live != m->kf_n)
		return -EUCLEAN;
	memset(m->mark, 0, (size_t)m->p.point_cap);
	for (int i = 0; i < m->n_free; i++) {
		int s = m->free_slots[i];
		if (s < 0 || s >= m->p.point_cap || m->mark[s] || m->pt[s].id != MVOD_MAP_NONE)
			return -EUCLEAN;
		m->mark[s] = 1;
	}
	for (int s = 0; s < m->p.point_cap; s++) {
		if (!m->mark[s] && (m->pt[s].id == MVOD_MAP_NONE || !point_ok(m, &m->pt[s])))
			return -EUCLEAN;
	}
	return 0;
}
