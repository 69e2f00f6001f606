#include "scale.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>

#include "mvod/geom.h"
#include "util/linalg.h"

/*
 * A point is on the plane when within this fraction of the camera's height of it: on the
 * mvod-synth street the ground's inliers lie within 1 % (ORB's 0.3 px at 5-15 baselines of
 * depth), a kerb 15 cm high under a 1.6 m camera is 9 % off.
 */
#define GROUND_BAND 0.04
/* RANSAC samples: with half the candidates on the ground, 1 - (1 - 0.5^3)^200 > 0.9999. */
#define GROUND_ITERATIONS 200

static bool below(const double *X)
{
	return X[1] > 0 && isfinite(X[0]) && isfinite(X[1]) && isfinite(X[2]);
}

/* Plane through a, b, c with its normal pointing down (y > 0); false when too tilted. */
static bool plane3(const double *a, const double *b, const double *c, struct mvod_ground *g)
{
	double u[3], v[3];
	for (int k = 0; k < 3; k++) {
		u[k] = b[k] - a[k];
		v[k] = c[k] - a[k];
	}
	double nx[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
			u[0] * v[1] - u[1] * v[0]};
	double len = mvod_vec3_norm(nx);
	if (!(len > 0))
		return false;
	double sign = nx[1] < 0 ? -1.0 : 1.0;
	for (int k = 0; k < 3; k++)
		g->n[k] = sign * nx[k] / len;
	g->h = g->n[0] * a[0] + g->n[1] * a[1] + g->n[2] * a[2];
	return g->n[1] >= cos(MVOD_GROUND_MAX_TILT_DEG * M_PI / 180) && g->h > 0;
}

static double plane_dist(const struct mvod_ground *g, const double *X)
{
	return fabs(g->n[0] * X[0] + g->n[1] * X[1] + g->n[2] * X[2] - g->h);
}

static int count_inliers(const double *X, int n, const struct mvod_ground *g)
{
	int c = 0;
	for (int i = 0; i < n; i++)
		c += below(X + 3 * i) && plane_dist(g, X + 3 * i) < GROUND_BAND * g->h;
	return c;
}

/* Least-squares plane through the inliers of g: the covariance's least singular direction. */
static void refit(const double *X, int n, struct mvod_ground *g)
{
	double c[3] = {0}, C[9] = {0};
	int m = 0;
	for (int i = 0; i < n; i++) {
		const double *p = X + 3 * i;
		if (!below(p) || plane_dist(g, p) >= GROUND_BAND * g->h)
			continue;
		for (int k = 0; k < 3; k++)
			c[k] += p[k];
		m++;
	}
	for (int k = 0; k < 3; k++)
		c[k] /= m > 0 ? m : 1;
	for (int i = 0; i < n; i++) {
		const double *p = X + 3 * i;
		if (!below(p) || plane_dist(g, p) >= GROUND_BAND * g->h)
			continue;
		for (int r = 0; r < 3; r++)
			for (int k = 0; k < 3; k++)
				C[3 * r + k] += (p[r] - c[r]) * (p[k] - c[k]);
	}
	double U[9], S[3], Vt[9];
	if (m < 3 || mvod_svd3(C, U, S, Vt) != 0)
		return;
	struct mvod_ground f;
	double sign = Vt[7] < 0 ? -1.0 : 1.0;
	for (int k = 0; k < 3; k++)
		f.n[k] = sign * Vt[6 + k];
	f.h = f.n[0] * c[0] + f.n[1] * c[1] + f.n[2] * c[2];
	f.inliers = count_inliers(X, n, &f);
	if (f.h > 0 && f.n[1] >= cos(MVOD_GROUND_MAX_TILT_DEG * M_PI / 180) && f.inliers >= g->inliers)
		*g = f;
}

int mvod_ground_fit(const double *X, int n, int min_inliers, struct mvod_ground *g)
{
	struct mvod_ground best = {.inliers = 0};
	uint32_t seed = 12345; /* fixed: the same points give the same plane */
	for (int it = 0; it < GROUND_ITERATIONS && n >= 3; it++) {
		int idx[3];
		for (int k = 0; k < 3; k++) {
			seed = seed * 1664525u + 1013904223u;
			idx[k] = (int)((seed >> 8) % (uint32_t)n);
		}
		const double *a = X + 3 * idx[0], *b = X + 3 * idx[1], *c = X + 3 * idx[2];
		struct mvod_ground cand;
		if (!below(a) || !below(b) || !below(c) || !plane3(a, b, c, &cand))
			continue;
		cand.inliers = count_inliers(X, n, &cand);
		if (cand.inliers > best.inliers)
			best = cand;
	}
	if (best.inliers < min_inliers || best.inliers < 3)
		return -ENODATA;
	refit(X, n, &best);
	*g = best;
	return 0;
}

void mvod_scale_filter_init(struct mvod_scale_filter *f, double gain, double gate)
{
	*f = (struct mvod_scale_filter){.gain = gain, .gate = gate, .since = -1};
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
	if (!first && fabs(r) > f->gate * (1 + f->refused)) {
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
