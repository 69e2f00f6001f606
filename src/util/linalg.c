#include "util/linalg.h"
#include "util/svd_shim.h"

#include "mvod/geom.h"

static void swap_d(double *a, double *b)
{
	double t = *a;
	*a = *b;
	*b = t;
}

double mvod_median(double *v, int n)
{
	/* Quickselect (Hoare): no allocation, linear on average. */
	int lo = 0, hi = n - 1, k = n / 2;
	while (lo < hi) {
		double pivot = v[(lo + hi) / 2];
		int i = lo, j = hi;
		while (i <= j) {
			while (v[i] < pivot)
				i++;
			while (v[j] > pivot)
				j--;
			if (i <= j)
				swap_d(&v[i++], &v[j--]);
		}
		if (k <= j)
			hi = j;
		else if (k >= i)
			lo = i;
		else
			break;
	}
	return v[k];
}

int mvod_nearest_rotation(const double C[9], double R[9], double *trace)
{
	/* C = U D V^T; R = U S V^T with S = diag(1, 1, +-1) so that R is a rotation, never a mirror. */
	double U[9], D[3], Vt[9];
	int ret = mvod_svd3(C, U, D, Vt);
	if (ret)
		return ret;
	double S[3] = {1, 1, mvod_mat3_det(U) * mvod_mat3_det(Vt) < 0 ? -1 : 1};
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++)
			R[3 * r + c] = U[3 * r] * S[0] * Vt[c] + U[3 * r + 1] * S[1] * Vt[3 + c] +
				       U[3 * r + 2] * S[2] * Vt[6 + c];
	if (trace)
		*trace = D[0] * S[0] + D[1] * S[1] + D[2] * S[2];
	return 0;
}
