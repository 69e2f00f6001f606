#include "project_match.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>

#include "vo/core/hamming.h"
#include "mvod/geom.h"

struct mvod_pm {
	struct mvod_pm_params p;
	int w, h, cols, rows, kp_cap;
	double radius_of[32];   /* search radius per octave, pixels */
	int *cell_start;        /* [cols * rows + 1]: cell c holds cell_kp[start[c]..start[c+1]) */
	int *cell_kp;           /* [kp_cap] keypoint indices sorted by cell */
	int *kp_owner, *kp_dist; /* [kp_cap] point holding each keypoint and its distance */
	const struct mvod_map_kp *kp;
	const uint8_t *desc;
	int n;
};

void mvod_pm_params_default(struct mvod_pm_params *p)
{
	*p = (struct mvod_pm_params){
		.radius_px = 15,
		.scale_factor = 1.2,
		.max_octave = 7,
		.max_dist = 100,
		.ratio = 0.8,
		.cell_px = 32,
	};
}

int mvod_pm_create(const struct mvod_pm_params *p, int width, int height, int kp_cap,
		   struct mvod_pm **out)
{
	*out = NULL;
	if (width < 1 || height < 1 || kp_cap < 1 || p->cell_px < 1 || !(p->radius_px > 0) ||
	    p->max_octave < 0 || p->max_octave >= 32 || !(p->scale_factor >= 1))
		return -EINVAL;
	struct mvod_pm *pm = calloc(1, sizeof(*pm));
	if (!pm)
		return -ENOMEM;
	pm->p = *p;
	pm->w = width;
	pm->h = height;
	pm->kp_cap = kp_cap;
	pm->cols = (width + p->cell_px - 1) / p->cell_px;
	pm->rows = (height + p->cell_px - 1) / p->cell_px;
	for (int o = 0; o <= p->max_octave; o++)
		pm->radius_of[o] = p->radius_px * pow(p->scale_factor, o);
	pm->cell_start = calloc((size_t)pm->cols * pm->rows + 1, sizeof(int));
	pm->cell_kp = calloc((size_t)kp_cap, sizeof(int));
	pm->kp_owner = calloc((size_t)kp_cap, sizeof(int));
	pm->kp_dist = calloc((size_t)kp_cap, sizeof(int));
	if (!pm->cell_start || !pm->cell_kp || !pm->kp_owner || !pm->kp_dist) {
		mvod_pm_destroy(pm);
		return -ENOMEM;
	}
	*out = pm;
	return 0;
}

void mvod_pm_destroy(struct mvod_pm *pm)
{
	if (!pm)
		return;
	free(pm->cell_start);
	free(pm->cell_kp);
	free(pm->kp_owner);
	free(pm->kp_dist);
	free(pm);
}

/* Cell of a pixel, clamped to the grid (keypoints sit within the image). */
static int cell_of(const struct mvod_pm *pm, double x, double y)
{
	int c = (int)(x / pm->p.cell_px), r = (int)(y / pm->p.cell_px);
	c = c < 0 ? 0 : c >= pm->cols ? pm->cols - 1 : c;
	r = r < 0 ? 0 : r >= pm->rows ? pm->rows - 1 : r;
	return r * pm->cols + c;
}

int mvod_pm_set_frame(struct mvod_pm *pm, const struct mvod_map_kp *kp, const uint8_t *desc,
		      int n)
{
	if (n < 0 || n > pm->kp_cap)
		return -EINVAL;
	for (int i = 0; i < n; i++)
		if (kp[i].octave < 0 || kp[i].octave > pm->p.max_octave)
			return -EINVAL;
	int cells = pm->cols * pm->rows;
	/* Counting sort by cell: counts, running ends, then each keypoint placed from the end
	 * (start[c] walks back to the cell's beginning). */
	for (int c = 0; c <= cells; c++)
		pm->cell_start[c] = 0;
	for (int i = 0; i < n; i++)
		pm->cell_start[cell_of(pm, kp[i].x, kp[i].y)]++;
	for (int c = 1; c <= cells; c++)
		pm->cell_start[c] += pm->cell_start[c - 1];
	for (int i = n - 1; i >= 0; i--)
		pm->cell_kp[--pm->cell_start[cell_of(pm, kp[i].x, kp[i].y)]] = i;
	pm->kp = kp;
	pm->desc = desc;
	pm->n = n;
	return 0;
}

/* Pixel of world point X; false when behind the camera or off the image. */
static bool project(const struct mvod_pm *pm, const double R[9], const double t[3],
		    const double K[4], const double X[3], double uv[2])
{
	double c[3];
	mvod_rigid_apply(R, t, X, c);
	return mvod_pinhole_pixel(K, c, uv) && uv[0] >= 0 && uv[0] < pm->w && uv[1] >= 0 && uv[1] < pm->h;
}

/* Keeps the two smallest distances (and the index of the smallest) of a search. */
static void consider(int h, int j, int *best, int *second, int *bi)
{
	if (h < *best) {
		*second = *best;
		*best = h;
		*bi = j;
	} else if (h < *second) {
		*second = h;
	}
}

/* Best keypoint for one point projected at uv: index (or -1), its distance, the second best. */
static int search(const struct mvod_pm *pm, const double uv[2], const uint8_t *d, int *best,
		  int *second)
{
	double rmax = pm->radius_of[pm->p.max_octave];
	int c0 = cell_of(pm, uv[0] - rmax, uv[1] - rmax);
	int c1 = cell_of(pm, uv[0] + rmax, uv[1] + rmax);
	int bi = -1;
	*best = *second = INT_MAX;
	for (int r = c0 / pm->cols; r <= c1 / pm->cols; r++) {
		int first = pm->cell_start[r * pm->cols + c0 % pm->cols];
		int end = pm->cell_start[r * pm->cols + c1 % pm->cols + 1];
		for (int e = first; e < end; e++) { /* the row's cells are contiguous */
			int j = pm->cell_kp[e];
			const struct mvod_map_kp *k = &pm->kp[j];
			double dx = k->x - uv[0], dy = k->y - uv[1], rad = pm->radius_of[k->octave];
			if (dx * dx + dy * dy <= rad * rad)
				consider(mvod_hamming256(d, pm->desc + (size_t)j * MVOD_MAP_DESC_BYTES),
					 j, best, second, &bi);
		}
	}
	return bi;
}

int mvod_pm_match(struct mvod_pm *pm, const double Rcw[9], const double tcw[3], const double K[4],
		  const double *pos, const uint8_t *desc, int n, int *match, int *dist)
{
	for (int j = 0; j < pm->n; j++)
		pm->kp_owner[j] = -1;
	int matched = 0;
	for (int i = 0; i < n; i++) {
		double uv[2];
		int best, second;
		match[i] = MVOD_PM_OUT_OF_VIEW;
		if (!project(pm, Rcw, tcw, K, pos + 3 * i, uv))
			continue;
		match[i] = MVOD_PM_UNMATCHED;
		int j = search(pm, uv, desc + (size_t)i * MVOD_MAP_DESC_BYTES, &best, &second);
		if (j < 0 || best > pm->p.max_dist || best >= pm->p.ratio * second)
			continue;
		int prev = pm->kp_owner[j];
		if (prev >= 0 && pm->kp_dist[j] <= best)
			continue; /* the keypoint's current owner is closer */
		if (prev >= 0) {
			match[prev] = MVOD_PM_UNMATCHED;
			matched--;
		}
		pm->kp_owner[j] = i;
		pm->kp_dist[j] = best;
		match[i] = j;
		matched++;
	}
	for (int i = 0; dist && i < n; i++)
		dist[i] = match[i] >= 0 ? pm->kp_dist[match[i]] : -1;
	return matched;
}
