#include "scale.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <stdio.h>
#include <stdlib.h>

#include "util/linalg.h"

/*
 * A point is on the ground when within this fraction of the camera's height of it along the
 * normal: the far ground points (50 baselines, 0.3 px) are ~2.6 % deep-noisy; a kerb 15 cm
 * high under a 1.6 m camera is 9 % off.
 */
#define GROUND_BAND 0.04
/* Second extent of the inliers against their first, at least (see refit_normal). */
#define GROUND_AREA 0.33
/* Heights tried: at most this many candidates' own, evenly spread over them. */
#define GROUND_HYPOTHESES 64

static bool below(const double *X)
{
	return X[1] > 0 && isfinite(X[0]) && isfinite(X[1]) && isfinite(X[2]);
}

static double dot3(const double *a, const double *b)
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Heights along prior of the points below the camera, into d; their count. */
static int heights(const double *X, int n, const double prior[3], double *d)
{
	int m = 0;
	for (int i = 0; i < n; i++)
		if (below(X + 3 * i) && dot3(prior, X + 3 * i) > 0)
			d[m++] = dot3(prior, X + 3 * i);
	return m;
}

/*
 * The lowest height among d[0..m) that at least half as many points support (within the band)
 * as the best supported one, and min_inliers: nothing real lies below the ground, while the
 * tops of cars and kerbs beside the road may gather more points than the road itself.
 */
static double lowest_height(const double *d, int m, int min_inliers)
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
	for (int i = 0; i < m && k <= GROUND_HYPOTHESES; i += step, k++)
		if (count[k] >= min_inliers && 2 * count[k] >= best && d[i] > h)
			h = d[i];
	return h;
}

/*
 * Least-squares normal of the points within the band of g (the covariance's least axis).
 * False when they do not spread over an area: a ground patch is wider and deeper than a
 * third of its longest extent, while a car's sill or a kerb's edge is a line.
 */
static bool refit_normal(const double *X, int n, const double prior[3], struct mvod_ground *g)
{
	double c[3] = {0}, C[9] = {0};
	int m = 0;
	for (int pass = 0; pass < 2; pass++) {
		for (int i = 0; i < n; i++) {
			const double *p = X + 3 * i;
			if (!below(p) || fabs(dot3(prior, p) - g->h) >= GROUND_BAND * g->h)
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
	if (mvod_svd3(C, U, S, Vt) != 0 || S[1] < GROUND_AREA * GROUND_AREA * S[0])
		return false;
	double sign = dot3(Vt + 6, prior) < 0 ? -1.0 : 1.0;
	for (int k = 0; k < 3; k++)
		g->n[k] = sign * Vt[6 + k];
	return true;
}

int mvod_ground_fit(const double *X, int n, const double prior[3], int min_inliers,
		    double *scratch, struct mvod_ground *g)
{
	int m = heights(X, n, prior, scratch);
	double h = lowest_height(scratch, m, min_inliers > 3 ? min_inliers : 3);
	if (h <= 0)
		return -ENODATA;
	int k = 0;
	for (int i = 0; i < m; i++)
		if (fabs(scratch[i] - h) < GROUND_BAND * h)
			scratch[k++] = scratch[i];
	g->h = mvod_median(scratch, k);
	if (getenv("GDEBUG")) { fprintf(stderr, "GFIT h=%.2f inl=%d m=%d:", g->h, k, m);
	  for (int i = 0; i < n; i++) { const double *p = X + 3*i; if (!below(p)) continue; double hh = dot3(prior, p); fprintf(stderr, " %.1f/%.0f/%.2f", hh, p[2], p[0]/p[2]); } fprintf(stderr, "\n"); }
	g->inliers = k;
	return refit_normal(X, n, prior, g) ? 0 : -ENODATA;
}

void mvod_ground_prior_update(double prior[3], const struct mvod_ground *g)
{
	if (dot3(prior, g->n) < cos(MVOD_GROUND_MAX_TURN_DEG * M_PI / 180))
		return;
	double len = 0;
	for (int k = 0; k < 3; k++)
		prior[k] += MVOD_GROUND_NORMAL_GAIN * (g->n[k] - prior[k]);
	len = sqrt(dot3(prior, prior));
	for (int k = 0; k < 3; k++)
		prior[k] /= len;
}

void mvod_scale_filter_init(struct mvod_scale_filter *f, double gain, double gate)
{
	*f = (struct mvod_scale_filter){.gain = gain, .gate = gate, .since = -1,
					.ground_n = {0, 1, 0}};
}

double mvod_scale_filter_step(struct mvod_scale_filter *f, double ratio, double quality,
			      bool *used)
{
	*used = false;
	if (f->since >= 0)
		f->since++;
	if (!(isfinite(ratio) && ratio > 0))
		return 1.0;
	double r = log(ratio);
	bool first = f->since < 0;
	/* Doubling: a scale that structure ran away with (1e13 on mvod-synth's 3.7 km KITTI 00
	 * path at a linear widening) is caught within a few dozen refusals. */
	if (!first && fabs(r) > ldexp(f->gate, f->refused < 60 ? f->refused : 60)) {
		f->refused++;
		return 1.0;
	}
	f->refused = 0;
	f->since = 0;
	f->quality = quality;
	*used = true;
	return first ? ratio : exp(f->gain * r);
}

bool mvod_scale_filter_metric(const struct mvod_scale_filter *f)
{
	return f->since >= 0;
}

double mvod_scale_filter_confidence(const struct mvod_scale_filter *f)
{
	return f->since < 0 ? 0.0 : f->quality * pow(MVOD_SCALE_DECAY, f->since);
}
