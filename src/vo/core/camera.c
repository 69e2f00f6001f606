/* The camera model helpers of the VO: the ground's normal from a mount, the road band. */
#include "camera.h"

#include <errno.h>

#include "mvod/geom.h"

void mvod_ground_normal(double pitch_deg, double roll_deg, double n[3])
{
	double p = pitch_deg * M_PI / 180, r = roll_deg * M_PI / 180;
	n[0] = cos(p) * sin(r);
	n[1] = cos(p) * cos(r);
	n[2] = sin(p);
}

/* A unit vector along the ground (perpendicular to n) from v; false when v is along n. */
static bool along_ground(const double n[3], const double v[3], double out[3])
{
	double d = mvod_vec3_dot(n, v), len = 0;
	for (int k = 0; k < 3; k++) {
		out[k] = v[k] - d * n[k];
		len += out[k] * out[k];
	}
	len = sqrt(len);
	for (int k = 0; k < 3; k++)
		out[k] /= len;
	return len > 1e-6;
}

int mvod_camera_band_quad(const struct mvod_camera *cam, const double n[3], float quad[8])
{
	static const double ez[3] = {0, 0, 1}, ex[3] = {1, 0, 0};
	/* Corners in order around the band: near left, near right, far right, far left. */
	static const double corner[4][2] = {{MVOD_BAND_NEAR, -MVOD_BAND_HALF_WIDTH},
					    {MVOD_BAND_NEAR, MVOD_BAND_HALF_WIDTH},
					    {MVOD_BAND_FAR, MVOD_BAND_HALF_WIDTH},
					    {MVOD_BAND_FAR, -MVOD_BAND_HALF_WIDTH}};
	double fwd[3], side[3];
	if (!along_ground(n, ez, fwd) || !along_ground(n, ex, side))
		return -EINVAL;
	for (int c = 0; c < 4; c++) {
		double P[3]; /* on the ground, in units of the camera's height */
		for (int k = 0; k < 3; k++)
			P[k] = n[k] + corner[c][0] * fwd[k] + corner[c][1] * side[k];
		if (!(P[2] > 0))
			return -EINVAL;
		quad[2 * c] = (float)(cam->fx * P[0] / P[2] + cam->cx);
		quad[2 * c + 1] = (float)(cam->fy * P[1] / P[2] + cam->cy);
	}
	return 0;
}

bool mvod_quad_contains(const float quad[8], float x, float y)
{
	int pos = 0, neg = 0;
	for (int c = 0; c < 4; c++) {
		const float *a = quad + 2 * c, *b = quad + 2 * ((c + 1) % 4);
		float cross = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
		pos += cross > 0;
		neg += cross < 0;
	}
	return !(pos && neg);
}
