#include "ground.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "mvod/geom.h"
#include "util/linalg.h"
#include "util/svd_shim.h"

/*
 * A point is on the ground when within this fraction of the camera's height of it along the
 * normal: the far ground points (50 baselines, 0.3 px) are ~2.6 % deep-noisy; a kerb 15 cm
 * high under a 1.6 m camera is 9 % off.
 */
#define GROUND_BAND 0.04
/*
 * Second extent (standard deviation) of the inliers against their first, at least (see
 * refit_normal). The road band (scale.h) is 4 heights wide and 13 deep: points spread evenly
 * over it have 0.31; a line of points (a kerb's edge, a car's sill) has its noise over its
 * length, under 0.05.
 */
#define GROUND_AREA 0.15
/*
 * Pitches tried about the expected normal's: +-4 deg in 0.5 deg steps. On KITTI 06 the band's
 * heights along (0, 1, 0) fell by 15 % from 7 to 13 m ahead (a 1.8 deg pitch between the
 * camera and the road), spreading them over 4 bands: no height had 20 points until the pitch
 * was searched. A pitch half a step off (0.25 deg) moves a point 13 heights ahead by 0.057
 * heights, beyond the +-0.04 band: such a step loses its farthest points; 0.25 deg steps
 * would double the search's cost (17 x 64 x m height counts).
 */
#define GROUND_PITCH_STEPS 8
#define GROUND_PITCH_STEP_DEG 0.5
/* Heights tried: at most this many candidates' own, evenly spread over them. */
#define GROUND_HYPOTHESES 64

static bool below(const double *X)
{
	return X[1] > 0 && isfinite(X[0]) && isfinite(X[1]) && isfinite(X[2]);
}

/* Heights along prior of the points below the camera, into d; their count. */
static int heights(const double *X, int n, const double prior[3], double *d)
{
	int m = 0;
	for (int i = 0; i < n; i++)
		if (below(X + 3 * i) && mvod_vec3_dot(prior, X + 3 * i) > 0)
			d[m++] = mvod_vec3_dot(prior, X + 3 * i);
	return m;
}

/*
 * The lowest height among d[0..m) that at least half as many points support (within the band)
 * as the best supported one, and min_inliers: nothing real lies below the ground, while the
 * tops of cars and kerbs beside the road may gather more points than the road itself.
 */
static double lowest_height(const double *d, int m, int min_inliers, int *support)
{
	int step = m > GROUND_HYPOTHESES ? m / GROUND_HYPOTHESES : 1, count[GROUND_HYPOTHESES + 1];
	int best = 0, k = 0;
	for (int i = 0; i < m && k <= GROUND_HYPOTHESES; i += step, k++) {
		count[k] = 0;
		for (int j = 0; j < m; j++)
			count[k] += fabs(d[j] - d[i]) < GROUND_BAND * d[i];
		best = count[k] > best ? count[k] : best;
	}
	double h = 0;
	k = 0;
	*support = 0;
	for (int i = 0; i < m && k <= GROUND_HYPOTHESES; i += step, k++)
		if (count[k] >= min_inliers && 2 * count[k] >= best && d[i] > h) {
			h = d[i];
			*support = count[k];
		}
	return h;
}

/*
 * Least-squares normal of the points within the band of g (the covariance's least axis).
 * False when they do not spread over an area: a ground patch is wider than GROUND_AREA of its
 * depth, while a car's sill or a kerb's edge is a line.
 */
static bool refit_normal(const double *X, int n, const double prior[3], struct mvod_ground *g)
{
	double c[3] = {0}, C[9] = {0};
	int m = 0;
	for (int pass = 0; pass < 2; pass++) {
		for (int i = 0; i < n; i++) {
			const double *p = X + 3 * i;
			if (!below(p) || fabs(mvod_vec3_dot(prior, p) - g->h) >= GROUND_BAND * g->h)
				continue;
			for (int r = 0; r < 3 && pass == 0; r++)
				c[r] += p[r];
			m += pass == 0;
			for (int r = 0; r < 9 && pass == 1; r++)
				C[r] += (p[r / 3] - c[r / 3]) * (p[r % 3] - c[r % 3]);
		}
		for (int r = 0; r < 3 && pass == 0; r++)
			c[r] /= m;
	}
	double U[9], S[3], Vt[9];
	memcpy(g->n, prior, sizeof(g->n));
	g->inliers = m;
	if (mvod_svd3(C, U, S, Vt) != 0 || S[1] < GROUND_AREA * GROUND_AREA * S[0])
		return false;
	double sign = mvod_vec3_dot(Vt + 6, prior) < 0 ? -1.0 : 1.0;
	for (int k = 0; k < 3; k++)
		g->n[k] = sign * Vt[6 + k];
	g->h = mvod_vec3_dot(g->n, c);
	memcpy(g->c, c, sizeof(g->c));
	return true;
}

/* prior turned by deg about the camera's x axis (a change of pitch), into out. */
static void pitched(const double prior[3], double deg, double out[3])
{
	double c = cos(deg * M_PI / 180), s = sin(deg * M_PI / 180);
	out[0] = prior[0];
	out[1] = c * prior[1] - s * prior[2];
	out[2] = s * prior[1] + c * prior[2];
}

/*
 * The pitch (within +-GROUND_PITCH_STEPS steps of GROUND_PITCH_STEP_DEG of prior's) whose
 * ground height the most points support, into best; that height, or 0 when none has
 * min_inliers. Zero pitch first, then outwards: a tie keeps the pitch nearest the prior's.
 */
static double best_pitch(const double *X, int n, const double prior[3], int min_inliers,
			 double *scratch, double best[3])
{
	double h = 0;
	int most = 0;
	for (int i = 0; i <= 2 * GROUND_PITCH_STEPS; i++) {
		double nn[3], hi;
		int support, step = (i + 1) / 2 * (i % 2 ? 1 : -1);
		pitched(prior, step * GROUND_PITCH_STEP_DEG, nn);
		hi = lowest_height(scratch, heights(X, n, nn, scratch), min_inliers, &support);
		if (hi > 0 && support > most) {
			most = support;
			h = hi;
			memcpy(best, nn, sizeof(nn));
		}
	}
	return h;
}

int mvod_ground_fit(const double *X, int n, const double prior[3], int min_inliers,
		    double *scratch, struct mvod_ground *g)
{
	double np[3];
	double h = best_pitch(X, n, prior, min_inliers > 3 ? min_inliers : 3, scratch, np);
	if (h <= 0)
		return -ENODATA;
	g->h = h;
	return refit_normal(X, n, np, g) ? 0 : -ENODATA;
}

/* prior moved towards g's normal by gain when within MVOD_GROUND_MAX_TURN_DEG, unit again. */
static void learn_normal(double prior[3], const struct mvod_ground *g, double gain)
{
	if (mvod_vec3_dot(prior, g->n) < cos(MVOD_GROUND_MAX_TURN_DEG * M_PI / 180))
		return;
	double len = 0;
	for (int k = 0; k < 3; k++)
		prior[k] += gain * (g->n[k] - prior[k]);
	len = sqrt(mvod_vec3_dot(prior, prior));
	for (int k = 0; k < 3; k++)
		prior[k] /= len;
}

void mvod_ground_prior_update(double prior[3], const struct mvod_ground *g)
{
	learn_normal(prior, g, MVOD_GROUND_NORMAL_GAIN);
}

/* ground_n made perpendicular to the mean direction of travel, once there is one. */
static void level_with_motion(struct mvod_scale_filter *f)
{
	if (f->motion_n == 0)
		return;
	double d = mvod_vec3_dot(f->ground_n, f->motion), l = 0;
	for (int k = 0; k < 3; k++) {
		f->ground_n[k] -= d * f->motion[k];
		l += f->ground_n[k] * f->ground_n[k];
	}
	for (int k = 0; k < 3; k++)
		f->ground_n[k] /= sqrt(l);
}

double mvod_ground_height_ratio(struct mvod_scale_filter *f, const double *X, int n,
				double height_m, double *scratch, double *q)
{
	struct mvod_ground g;
	*q = 0;
	if (mvod_ground_fit(X, n, f->ground_n, MVOD_GROUND_MIN_INLIERS, scratch, &g) != 0)
		return NAN;
	bool level = mvod_vec3_dot(f->ground_n, g.n) >= cos(f->max_tilt_deg * M_PI / 180);
	f->tilted = level ? 0 : f->tilted + 1;
	if (level || f->since < 0 || f->tilted > MVOD_GROUND_TILTED_RUN) {
		/*
		 * The mean of the first fits, then a slow average: from the level guess at 0.1 a
		 * fit, KITTI 06's normal was still 0.4 deg below its fits' mean (1.0 deg) after 20
		 * fits, and its two-view steps ran 7.5 % long (mean log ratio to the truth).
		 */
		double gain = 1.0 / (f->normal_fits + 1);
		learn_normal(f->ground_n, &g, fmax(gain, MVOD_GROUND_NORMAL_GAIN));
		f->normal_fits++;
	}
	level_with_motion(f);
	/* A tilted fit still measures: along the expected normal its tilt costs nothing. */
	double h = mvod_vec3_dot(f->ground_n, g.c);
	if (!(h > 0))
		return NAN;
	/* Saturates: 20 inliers give 0.5, 80 give 0.8. */
	*q = g.inliers / (g.inliers + 20.0);
	return height_m / h;
}
