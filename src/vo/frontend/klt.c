/*
 * The KLT front end's bookkeeping in plain C: tracks in fixed-capacity arrays, the
 * forward-backward check, Harris ranking of FAST corners and their spread over a grid.
 * Lucas-Kanade is lk.c's; OpenCV's part (pyramid levels, FAST) is behind klt_shim.h.
 */
#include "klt.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "klt_shim.h"
#include "vo/core/camera.h"
#include "util/kernels.h"

/*
 * Lucas-Kanade window, pixels, and pyramid levels above the image, with at most ITERATIONS
 * steps per level down to a step of EPS_PX (lk.h). OpenCV's defaults are 21, 3, 30,
 * 0.01; on KITTI 06 with 500 tracks they cost 1.25e9 instructions in LK over 5 frames
 * (callgrind), 21, 3, 10, 0.03 cost 0.90e9 at the same err_avg. A 21 px window on 3 levels
 * finds the 31 px flow of a track with no prediction (mvod-synth's rotate-in-place,
 * tests/integration/test_klt.c: 287 of 500 kept; 15 px on 2 levels kept 26). It serves the
 * frame after a start or reset, when no track has a measured flow.
 */
#define WIN 21
#define LEVELS 3
#define ITERATIONS 10
#define EPS_PX 0.03
/*
 * Tracks with a predicted flow (their own last displacement, or their neighbours') search with
 * a SEARCH_WIN window on the same levels, then refine with the WIN window on level 0 only:
 * KITTI 06, 226.0e6 -> 120.6e6 instructions per frame (BENCHMARKS.md, "Initial flow for every
 * track"). The search alone (no refinement) at 9 px failed test_klt.c's turn on mvod-synth's
 * smooth texture, which the full window at full resolution keeps as precise as before; the
 * backward check is not refined (forward_back()).
 */
#define SEARCH_WIN 9
/*
 * New tracks start at FAST corners of the coarsest pyramid level at least DETECT_MIN_W pixels wide
 * (positions times 2^level), at fast_threshold halved per level (a level's pixel averages four of
 * the one below, so fine texture loses about half its contrast), ranked by the Harris score at
 * level 0. On KITTI's 1226-1241 px (level 1) FAST then reads a quarter of the pixels: 85.6e6 ->
 * 80.3e6 instructions per frame on 06 (FAST 10.2e6 -> 5.8e6), as many new tracks living about as
 * long (past their first step: 29 % on 06, 45 % on 07; 30 and 47 % before, BENCHMARKS.md "Where
 * new tracks die"). 12 KLT map rows of the clips, mean over --tracks 480/500/520: gt err_avg
 * 0.0492 -> 0.0482, ATE 0.187 -> 0.183 m, 07's free-scale drift 1.163 -> 1.121 (each draw under
 * 1.15); mvod-synth's 1240x376 drives along KITTI 06 and 07 (map auto and height, same draws):
 * t_rel 1.28 -> 1.13 %. At threshold 20 on level 1: 75.4e6, but 07's drift 1.194 and its height's
 * ATE 0.384 -> 0.507 m. Frames under 1024 px stay at level 0 (KITTI's level 1, 613-620 px, passes
 * DETECT_MIN_W; a 640 px frame's 320 px one does not): on mvod-synth's 320x240 stop-go, level 1
 * (threshold 20) moved the standing camera 4 times as far a frame, over the bound of
 * tests/integration/test_sequences.c's test_map_stop_go.
 */
#define DETECT_MIN_W 512
/* A bucket's median displacement predicts its new tracks when it holds this many measured. */
#define MIN_NEIGHBOURS 3
/*
 * Corners and tracks stay this many pixels inside the image: the Harris score's 7x7 window
 * and its central differences reach 4 pixels out.
 */
#define BORDER 4
/* At most one track per cell of OCC_PX x OCC_PX pixels: no two tracks follow one corner. */
#define OCC_PX 6
/* Detection's grid: each of BUCKETS_X x BUCKETS_Y cells first gets its share of max_tracks. */
#define BUCKETS_X 8
#define BUCKETS_Y 4

struct corner {
	float x, y, score;
};

struct mvod_klt {
	struct mvod_klt_params p;
	struct mvod_klt_cv *cv;
	/* The pyramids' levels for lk.c: older (the last frame) and newest (this one); nlev each. */
	struct mvod_lk_level older[LEVELS + 1], newest[LEVELS + 1];
	int nlev;
	int w, h;
	int detect_level; /* pyramid level detect() runs FAST on (DETECT_MIN_W) */
	int n;       /* live tracks */
	int have_prev; /* a frame was tracked before (since create or reset) */
	float *pos;  /* 2 * max_tracks: position in the last frame, pixels */
	float *vel;  /* 2 * max_tracks: displacement over the last frame: the predicted flow */
	float *err;  /* max_tracks: last forward-backward error, pixels */
	float *score; /* max_tracks: Harris score at detection */
	int *ref;    /* max_tracks: index in the reference frame, -1 when it holds no such track */
	uint8_t *fresh; /* max_tracks: 1 = started on the last frame, no displacement measured */
	uint8_t *cell;  /* max_tracks: bucket of pos (predict's scratch) */
	float *next, *back; /* 2 * max_tracks: forward and backward LK results */
	uint8_t *ok, *ok_back, *sel; /* max_tracks; sel: which tracks a pass takes (flow_some) */
	int fast_cap;
	float *fast_xy;      /* 2 * fast_cap */
	struct corner *corners; /* fast_cap (>= max_tracks: predict's scratch too) */
	int occ_w, occ_h;
	uint8_t *occ;        /* occ_w * occ_h occupancy of OCC_PX cells */
	int bucket[BUCKETS_X * BUCKETS_Y];
};

void mvod_klt_params_default(struct mvod_klt_params *p)
{
	/* fb_px: 0.5 px passes every track of a textured rotating scene (tests/integration/test_klt.c). */
	*p = (struct mvod_klt_params){.max_tracks = 500, .fb_px = 0.5, .fast_threshold = 20};
}

static int alloc_arrays(struct mvod_klt *k)
{
	size_t n = (size_t)k->p.max_tracks;
	k->pos = calloc(2 * n, sizeof(float));
	k->vel = calloc(2 * n, sizeof(float));
	k->err = calloc(n, sizeof(float));
	k->score = calloc(n, sizeof(float));
	k->ref = calloc(n, sizeof(int));
	k->fresh = calloc(n, 1);
	k->cell = calloc(n, 1);
	k->next = calloc(2 * n, sizeof(float));
	k->back = calloc(2 * n, sizeof(float));
	k->ok = calloc(n, 1);
	k->ok_back = calloc(n, 1);
	k->sel = calloc(n, 1);
	k->fast_xy = calloc(2 * (size_t)k->fast_cap, sizeof(float));
	k->corners = calloc((size_t)k->fast_cap, sizeof(*k->corners));
	k->occ = calloc((size_t)k->occ_w * (size_t)k->occ_h, 1);
	return k->pos && k->vel && k->err && k->score && k->ref && k->fresh && k->cell && k->next &&
			       k->back && k->ok && k->ok_back && k->sel && k->fast_xy && k->corners &&
			       k->occ
		       ? 0
		       : -ENOMEM;
}

int mvod_klt_create(const struct mvod_klt_params *p, int width, int height, struct mvod_klt **out)
{
	if (p->max_tracks < 1 || !(p->fb_px > 0) || p->fast_threshold < 1 ||
	    width < 2 * BORDER + 1 || height < 2 * BORDER + 1)
		return -EINVAL;
	struct mvod_klt *k = calloc(1, sizeof(*k));
	if (!k)
		return -ENOMEM;
	k->p = *p;
	k->w = width;
	k->h = height;
	/* FAST finds about 1 corner per 100 pixels on KITTI at threshold 20; one per 16 is room. */
	k->fast_cap = width * height / 16 + 16;
	if (k->fast_cap < p->max_tracks)
		k->fast_cap = p->max_tracks;
	while (k->detect_level < LEVELS && width >> (k->detect_level + 1) >= DETECT_MIN_W)
		k->detect_level++;
	k->occ_w = (width + OCC_PX - 1) / OCC_PX;
	k->occ_h = (height + OCC_PX - 1) / OCC_PX;
	int ret = alloc_arrays(k);
	if (!ret)
		ret = mvod_klt_cv_create(width, height, WIN, LEVELS, k->fast_cap, &k->cv);
	if (ret) {
		mvod_klt_destroy(k);
		return ret;
	}
	*out = k;
	return 0;
}

void mvod_klt_destroy(struct mvod_klt *k)
{
	if (!k)
		return;
	mvod_klt_cv_destroy(k->cv);
	free(k->pos);
	free(k->vel);
	free(k->err);
	free(k->score);
	free(k->ref);
	free(k->fresh);
	free(k->cell);
	free(k->next);
	free(k->back);
	free(k->ok);
	free(k->ok_back);
	free(k->sel);
	free(k->fast_xy);
	free(k->corners);
	free(k->occ);
	free(k);
}

static bool inside(const struct mvod_klt *k, float x, float y)
{
	return x >= BORDER && y >= BORDER && x <= k->w - 1 - BORDER && y <= k->h - 1 - BORDER;
}

/* Harris corner score over the 7x7 window around (x, y) (util/kernels.c). */
static float harris(const struct mvod_image *g, int x, int y)
{
	/*
	 * Reads bytes x-4 .. x+5 of rows y-3 .. y+3 and x-3 .. x+4 of rows y-4 and y+4: inside()
	 * keeps x and y BORDER (4) from the edges, so x+5 on row y+3 <= h-2 is at worst the first
	 * byte of the next row, in the image.
	 */
	return mvod_harris7(g->data + (size_t)y * (size_t)g->stride + (size_t)x, g->stride);
}

/*
 * Strongest first, by Shell sort (Ciura's gaps) in place: glibc's qsort mallocs a buffer for
 * arrays over 1 kB, which tests/integration/test_alloc.c caught (0.2 calls per frame).
 */
static void sort_by_score(struct corner *c, int n)
{
	static const int gaps[] = {1750, 701, 301, 132, 57, 23, 10, 4, 1};
	for (size_t g = 0; g < sizeof(gaps) / sizeof(gaps[0]); g++) {
		for (int i = gaps[g]; i < n; i++) {
			struct corner x = c[i];
			int j = i;
			for (; j >= gaps[g] && c[j - gaps[g]].score < x.score; j -= gaps[g])
				c[j] = c[j - gaps[g]];
			c[j] = x;
		}
	}
}

static int occ_index(const struct mvod_klt *k, float x, float y)
{
	return (int)(y / OCC_PX) * k->occ_w + (int)(x / OCC_PX);
}

static int bucket_index(const struct mvod_klt *k, float x, float y)
{
	return (int)(y * BUCKETS_Y / k->h) * BUCKETS_X + (int)(x * BUCKETS_X / k->w);
}

/*
 * Marks the cells of the live tracks, dropping the younger of two tracks that converged on one
 * cell (tracks are kept oldest first), and counts them per bucket.
 */
static void mark_tracks(struct mvod_klt *k)
{
	memset(k->occ, 0, (size_t)k->occ_w * (size_t)k->occ_h);
	memset(k->bucket, 0, sizeof(k->bucket));
	int m = 0;
	for (int i = 0; i < k->n; i++) {
		float x = k->pos[2 * i], y = k->pos[2 * i + 1];
		int o = occ_index(k, x, y);
		if (k->occ[o])
			continue;
		k->occ[o] = 1;
		k->bucket[bucket_index(k, x, y)]++;
		k->pos[2 * m] = x;
		k->pos[2 * m + 1] = y;
		k->vel[2 * m] = k->vel[2 * i];
		k->vel[2 * m + 1] = k->vel[2 * i + 1];
		k->err[m] = k->err[i];
		k->score[m] = k->score[i];
		k->ref[m] = k->ref[i];
		k->fresh[m] = k->fresh[i];
		m++;
	}
	k->n = m;
}

/* Track j starts at corner c, with no flow yet and no match in the reference. */
static void start_track(struct mvod_klt *k, int j, const struct corner *c)
{
	k->pos[2 * j] = c->x;
	k->pos[2 * j + 1] = c->y;
	k->vel[2 * j] = k->vel[2 * j + 1] = 0;
	k->err[j] = 0;
	k->score[j] = c->score;
	k->ref[j] = -1;
	k->fresh[j] = 1;
}

/* New tracks from the ranked corners, strongest first, in free cells; quota: per bucket, or 0. */
static void add_corners(struct mvod_klt *k, int nc, int quota)
{
	for (int i = 0; i < nc && k->n < k->p.max_tracks; i++) {
		const struct corner *c = &k->corners[i];
		int o = occ_index(k, c->x, c->y), b = bucket_index(k, c->x, c->y);
		if (k->occ[o] || (quota && k->bucket[b] >= quota))
			continue;
		k->occ[o] = 1;
		k->bucket[b]++;
		start_track(k, k->n++, c);
	}
}

/*
 * Tops the tracks up with FAST corners ranked by Harris score: first each grid bucket up to
 * its share of max_tracks, so that no part of the image is left without tracks, then the
 * strongest of the rest anywhere. A corner in a cell a track holds is never taken
 * (add_corners), so it is neither scored nor sorted.
 */
static int detect(struct mvod_klt *k, const struct mvod_image *grey)
{
	int nf;
	int ret = mvod_klt_cv_fast_level(k->cv, k->detect_level,
					 k->p.fast_threshold >> k->detect_level, k->fast_xy, &nf);
	if (ret)
		return ret;
	mark_tracks(k);
	int nc = 0;
	for (int i = 0; i < nf; i++) {
		float x = k->fast_xy[2 * i], y = k->fast_xy[2 * i + 1];
		float s = inside(k, x, y) && !k->occ[occ_index(k, x, y)] ? harris(grey, (int)x, (int)y)
									 : 0;
		if (s > 0) /* not an edge or a flat patch */
			k->corners[nc++] = (struct corner){x, y, s};
	}
	sort_by_score(k->corners, nc);
	int cells = BUCKETS_X * BUCKETS_Y;
	add_corners(k, nc, (k->p.max_tracks + cells - 1) / cells);
	add_corners(k, nc, 0);
	return 0;
}

/*
 * Median of displacement component c (0: x, 1: y) over the measured tracks of bucket b (-1:
 * every bucket); *count: how many. k->corners is the scratch.
 */
static float median_flow(struct mvod_klt *k, int b, int c, int *count)
{
	int m = 0;
	for (int i = 0; i < k->n; i++)
		if (!k->fresh[i] && (b < 0 || k->cell[i] == b))
			k->corners[m++].score = k->vel[2 * i + c];
	*count = m;
	if (!m)
		return 0;
	sort_by_score(k->corners, m);
	return k->corners[m / 2].score;
}

/*
 * The initial flow of the tracks started on the last frame (no displacement measured yet): the
 * median displacement of the measured tracks of their bucket when it holds MIN_NEIGHBOURS,
 * else of every measured track. Returns false when fewer than MIN_NEIGHBOURS are measured.
 */
static bool predict(struct mvod_klt *k)
{
	int fresh[BUCKETS_X * BUCKETS_Y] = {0}, all;
	for (int i = 0; i < k->n; i++) {
		k->cell[i] = (uint8_t)bucket_index(k, k->pos[2 * i], k->pos[2 * i + 1]);
		fresh[k->cell[i]] += k->fresh[i];
	}
	float gx = median_flow(k, -1, 0, &all), gy = median_flow(k, -1, 1, &all);
	if (all < MIN_NEIGHBOURS)
		return false;
	for (int b = 0; b < BUCKETS_X * BUCKETS_Y; b++) {
		if (!fresh[b])
			continue;
		int m;
		float x = median_flow(k, b, 0, &m), y = median_flow(k, b, 1, &m);
		for (int i = 0; i < k->n; i++) {
			if (k->fresh[i] && k->cell[i] == b) {
				k->vel[2 * i] = m >= MIN_NEIGHBOURS ? x : gx;
				k->vel[2 * i + 1] = m >= MIN_NEIGHBOURS ? y : gy;
			}
		}
	}
	return true;
}

/*
 * Lucas-Kanade (lk.h) of n points from the older pyramid to the newest (backward = 0) or back,
 * with a win x win window on levels levels .. 0 (fewer when the pyramids have fewer).
 */
static void flow(struct mvod_klt *k, int backward, int win, int levels, const float *from,
		 float *to, int n, uint8_t *ok)
{
	struct mvod_lk_params p = {.win = win,
				   .levels = levels < k->nlev - 1 ? levels : k->nlev - 1,
				   .iterations = ITERATIONS,
				   .eps_px = EPS_PX};
	mvod_lk_flow(backward ? k->newest : k->older, backward ? k->older : k->newest, &p, from, to,
		     n, ok);
}

/*
 * Lucas-Kanade of the points i < n with sel[i] set, from[i] to to[i] (which holds the guess),
 * ok[i] saying which converged; ok[i] = 0 where sel[i] is not set, to[i] left as it was. LK
 * treats every point on its own, so a point's result is the same whether or not the others
 * are passed: a pass skips the tracks an earlier pass already dropped, at no change to any
 * trajectory (BENCHMARKS.md, "Bit-identical cuts"). sel may be ok.
 */
static void flow_some(struct mvod_klt *k, int backward, int win, int levels, const float *from,
		      float *to, int n, const uint8_t *sel, uint8_t *ok)
{
	for (int i = 0; i < n; i++) {
		if (sel[i])
			flow(k, backward, win, levels, from + 2 * i, to + 2 * i, 1, ok + i);
		else
			ok[i] = 0;
	}
}

/*
 * Every track forward from pos with vel (its displacement) as the initial flow into next, then
 * back into back with vel undone as the guess; ok and ok_back say which converged. With a
 * predicted flow a SEARCH_WIN search on the pyramid, then, forward only, WIN on level 0 from
 * its result; without, WIN on every level. The backward pass only checks the forward one
 * against fb_px: unrefined, KITTI 06 costs 101.6e6 instead of 120.6e6 instructions per frame,
 * err_avg 06 / 07 0.072 / 0.043 against 0.079 / 0.050 (BENCHMARKS.md). The refinement takes
 * the tracks the search kept, the backward pass those still kept and inside the image
 * (kept() drops the others whatever their backward result).
 */
static void forward_back(struct mvod_klt *k, bool predicted)
{
	int n = k->n, win = predicted ? SEARCH_WIN : WIN;
	for (int i = 0; i < 2 * n; i++)
		k->next[i] = k->pos[i] + k->vel[i];
	flow(k, 0, win, LEVELS, k->pos, k->next, n, k->ok);
	if (predicted)
		flow_some(k, 0, WIN, 0, k->pos, k->next, n, k->ok, k->ok);
	for (int i = 0; i < n; i++) {
		k->back[2 * i] = k->next[2 * i] - k->vel[2 * i];
		k->back[2 * i + 1] = k->next[2 * i + 1] - k->vel[2 * i + 1];
		k->sel[i] = k->ok[i] && inside(k, k->next[2 * i], k->next[2 * i + 1]);
	}
	flow_some(k, 1, win, LEVELS, k->next, k->back, n, k->sel, k->ok_back);
}

/* Track i survives: both ways converged, it came back within fb_px (*fb) and is inside. */
static bool kept(const struct mvod_klt *k, int i, float *fb)
{
	*fb = hypotf(k->back[2 * i] - k->pos[2 * i], k->back[2 * i + 1] - k->pos[2 * i + 1]);
	return k->ok[i] && k->ok_back[i] && *fb <= k->p.fb_px &&
	       inside(k, k->next[2 * i], k->next[2 * i + 1]);
}

/*
 * Every track into the newest frame, forward and back (forward_back) from its predicted flow;
 * a track stays when kept() says so.
 */
static void follow(struct mvod_klt *k)
{
	forward_back(k, predict(k));
	int m = 0;
	float fb;
	for (int i = 0; i < k->n; i++) {
		if (!kept(k, i, &fb))
			continue;
		k->vel[2 * m] = k->next[2 * i] - k->pos[2 * i];
		k->vel[2 * m + 1] = k->next[2 * i + 1] - k->pos[2 * i + 1];
		k->pos[2 * m] = k->next[2 * i];
		k->pos[2 * m + 1] = k->next[2 * i + 1];
		k->err[m] = fb;
		k->score[m] = k->score[i];
		k->ref[m] = k->ref[i];
		k->fresh[m] = 0;
		m++;
	}
	k->n = m;
}

int mvod_klt_track(struct mvod_klt *k, const struct mvod_image *grey, struct mvod_features *f,
		   struct mvod_match *matches, int *n_matches)
{
	if (f->cap < k->p.max_tracks)
		return -EINVAL;
	int ret = mvod_klt_cv_push(k->cv, grey);
	if (ret)
		return ret;
	k->nlev = mvod_klt_cv_levels(k->cv, 0, k->older, LEVELS + 1);
	mvod_klt_cv_levels(k->cv, 1, k->newest, LEVELS + 1);
	if (k->have_prev && k->nlev > 0)
		follow(k);
	k->have_prev = 1;
	/* Topping up at 3/4: a KITTI frame loses up to a tenth of its tracks. */
	if (k->n < k->p.max_tracks * 3 / 4 && (ret = detect(k, grey)))
		return ret;
	int m = 0;
	for (int i = 0; i < k->n; i++) {
		f->kp[i] = (struct mvod_keypoint){k->pos[2 * i], k->pos[2 * i + 1], 0, k->score[i]};
		if (k->ref[i] >= 0)
			matches[m++] = (struct mvod_match){k->ref[i], i, k->err[i]};
	}
	f->n = k->n;
	*n_matches = m;
	return 0;
}

/* FAST corners of the rows quad spans that lie inside it, ranked into k->corners, *nc of them. */
static int band_corners(struct mvod_klt *k, const struct mvod_image *grey, const float quad[8],
			int threshold, int *nc)
{
	float y0 = quad[1], y1 = quad[1];
	for (int c = 1; c < 4; c++) {
		y0 = fminf(y0, quad[2 * c + 1]);
		y1 = fmaxf(y1, quad[2 * c + 1]);
	}
	int top = y0 > BORDER ? (int)y0 : BORDER, bottom = y1 < k->h ? (int)y1 : k->h;
	*nc = 0;
	if (bottom - top < 2 * BORDER + 1)
		return 0;
	/* FAST on the band's rows only: a view into grey. */
	struct mvod_image rows = *grey;
	rows.data = grey->data + (size_t)top * (size_t)grey->stride;
	rows.h = bottom - top;
	int nf, ret = mvod_klt_cv_fast(k->cv, &rows, threshold, k->fast_xy, &nf);
	for (int i = 0; i < nf && !ret; i++) {
		float x = k->fast_xy[2 * i], y = k->fast_xy[2 * i + 1] + (float)top;
		float s = inside(k, x, y) && mvod_quad_contains(quad, x, y) ? harris(grey, (int)x, (int)y)
									    : 0;
		if (s > 0)
			k->corners[(*nc)++] = (struct corner){x, y, s};
	}
	sort_by_score(k->corners, *nc);
	return ret;
}

/* The slot a new band track takes: free capacity, else the youngest unmatched track outside. */
static int band_slot(struct mvod_klt *k, const float quad[8], int *victim)
{
	if (k->n < k->p.max_tracks)
		return k->n++;
	for (; *victim >= 0; (*victim)--) {
		int j = *victim;
		if (k->ref[j] < 0 && !mvod_quad_contains(quad, k->pos[2 * j], k->pos[2 * j + 1]))
			return (*victim)--;
	}
	return -1;
}

int mvod_klt_reserve(struct mvod_klt *k, const struct mvod_image *grey, const float quad[8],
		     int share, int band_threshold, struct mvod_features *f)
{
	int have = 0, nc, victim = k->n - 1, n_added = 0;
	memset(k->occ, 0, (size_t)k->occ_w * (size_t)k->occ_h);
	for (int i = 0; i < k->n; i++) {
		have += mvod_quad_contains(quad, k->pos[2 * i], k->pos[2 * i + 1]);
		k->occ[occ_index(k, k->pos[2 * i], k->pos[2 * i + 1])] = 1;
	}
	int ret = have < share ? band_corners(k, grey, quad, band_threshold, &nc) : (nc = 0);
	for (int i = 0; i < nc && have + n_added < share && !ret; i++) {
		const struct corner *c = &k->corners[i];
		int o = occ_index(k, c->x, c->y), j;
		if (k->occ[o])
			continue;
		if ((j = band_slot(k, quad, &victim)) < 0)
			break;
		k->occ[o] = 1;
		start_track(k, j, c);
		f->kp[j] = (struct mvod_keypoint){c->x, c->y, 0, c->score};
		n_added++;
	}
	f->n = k->n;
	return ret;
}

void mvod_klt_promote(struct mvod_klt *k)
{
	for (int i = 0; i < k->n; i++)
		k->ref[i] = i;
}

void mvod_klt_reset(struct mvod_klt *k)
{
	if (!k)
		return;
	k->n = 0;
	k->have_prev = 0;
}
