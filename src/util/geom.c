#include "mvod/geom.h"

#include <math.h>
#include <string.h>

void mvod_pose_identity(struct mvod_pose *p)
{
	static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
	memcpy(p->R, I, sizeof(I));
	p->t[0] = p->t[1] = p->t[2] = 0.0;
}

void mvod_mat3_mul(const double A[9], const double B[9], double C[9])
{
	double tmp[9];
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			tmp[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
	memcpy(C, tmp, sizeof(tmp));
}

void mvod_mat3_mul_bt(const double A[9], const double B[9], double C[9])
{
	double tmp[9];
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			tmp[3 * i + j] = A[3 * i] * B[3 * j] + A[3 * i + 1] * B[3 * j + 1] +
					 A[3 * i + 2] * B[3 * j + 2];
	memcpy(C, tmp, sizeof(tmp));
}

void mvod_mat3_mul_at(const double A[9], const double B[9], double C[9])
{
	double tmp[9];
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			tmp[3 * i + j] = A[i] * B[j] + A[3 + i] * B[3 + j] + A[6 + i] * B[6 + j];
	memcpy(C, tmp, sizeof(tmp));
}

void mvod_mat3_vec(const double A[9], const double v[3], double out[3])
{
	double tmp[3];
	for (int i = 0; i < 3; i++)
		tmp[i] = A[3 * i] * v[0] + A[3 * i + 1] * v[1] + A[3 * i + 2] * v[2];
	memcpy(out, tmp, sizeof(tmp));
}

void mvod_rigid_apply(const double R[9], const double t[3], const double X[3], double out[3])
{
	mvod_mat3_vec(R, X, out);
	for (int k = 0; k < 3; k++)
		out[k] += t[k];
}

void mvod_rigid_scale(const double R[9], double t[3], const double centre[3], double s)
{
	for (int r = 0; r < 3; r++)
		t[r] = s * t[r] + (s - 1) * (R[3 * r] * centre[0] + R[3 * r + 1] * centre[1] +
					     R[3 * r + 2] * centre[2]);
}

bool mvod_pinhole_pixel(const double K[4], const double c[3], double uv[2])
{
	if (!(c[2] > 0))
		return false;
	uv[0] = K[0] * c[0] / c[2] + K[2];
	uv[1] = K[1] * c[1] / c[2] + K[3];
	return true;
}

void mvod_mat3_tvec(const double A[9], const double v[3], double out[3])
{
	double tmp[3];
	for (int i = 0; i < 3; i++)
		tmp[i] = A[i] * v[0] + A[3 + i] * v[1] + A[6 + i] * v[2];
	memcpy(out, tmp, sizeof(tmp));
}

void mvod_motion_between(const double Ra[9], const double ta[3], const double Rb[9],
			 const double tb[3], double R[9], double t[3])
{
	double v[3];
	mvod_mat3_mul_bt(Rb, Ra, R);
	mvod_mat3_vec(R, ta, v);
	for (int k = 0; k < 3; k++)
		t[k] = tb[k] - v[k];
}

double mvod_vec3_norm(const double v[3])
{
	return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

double mvod_vec3_dist(const double a[3], const double b[3])
{
	double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
	return mvod_vec3_norm(d);
}

double mvod_mat3_det(const double A[9])
{
	return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
	       A[2] * (A[3] * A[7] - A[4] * A[6]);
}

void mvod_pose_compose(const struct mvod_pose *a, const struct mvod_pose *b, struct mvod_pose *out)
{
	struct mvod_pose r;
	mvod_mat3_mul(a->R, b->R, r.R);
	mvod_mat3_vec(a->R, b->t, r.t);
	for (int i = 0; i < 3; i++)
		r.t[i] += a->t[i];
	*out = r;
}

void mvod_pose_inverse(const struct mvod_pose *a, struct mvod_pose *out)
{
	struct mvod_pose r;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			r.R[3 * i + j] = a->R[3 * j + i];
	mvod_mat3_vec(r.R, a->t, r.t);
	for (int i = 0; i < 3; i++)
		r.t[i] = -r.t[i];
	*out = r;
}

void mvod_rot_to_quat(const double R[9], double q[4])
{
	double tr = R[0] + R[4] + R[8];
	double w, x, y, z;
	if (tr > 0) {
		double s = 2.0 * sqrt(tr + 1.0);
		w = 0.25 * s;
		x = (R[7] - R[5]) / s;
		y = (R[2] - R[6]) / s;
		z = (R[3] - R[1]) / s;
	} else if (R[0] > R[4] && R[0] > R[8]) {
		double s = 2.0 * sqrt(1.0 + R[0] - R[4] - R[8]);
		w = (R[7] - R[5]) / s;
		x = 0.25 * s;
		y = (R[1] + R[3]) / s;
		z = (R[2] + R[6]) / s;
	} else if (R[4] > R[8]) {
		double s = 2.0 * sqrt(1.0 + R[4] - R[0] - R[8]);
		w = (R[2] - R[6]) / s;
		x = (R[1] + R[3]) / s;
		y = 0.25 * s;
		z = (R[5] + R[7]) / s;
	} else {
		double s = 2.0 * sqrt(1.0 + R[8] - R[0] - R[4]);
		w = (R[3] - R[1]) / s;
		x = (R[2] + R[6]) / s;
		y = (R[5] + R[7]) / s;
		z = 0.25 * s;
	}
	double n = sqrt(w * w + x * x + y * y + z * z);
	if (w < 0)
		n = -n;
	q[0] = w / n;
	q[1] = x / n;
	q[2] = y / n;
	q[3] = z / n;
}

void mvod_quat_to_rot(const double q[4], double R[9])
{
	double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
	double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
	R[0] = 1 - 2 * (y * y + z * z);
	R[1] = 2 * (x * y - z * w);
	R[2] = 2 * (x * z + y * w);
	R[3] = 2 * (x * y + z * w);
	R[4] = 1 - 2 * (x * x + z * z);
	R[5] = 2 * (y * z - x * w);
	R[6] = 2 * (x * z - y * w);
	R[7] = 2 * (y * z + x * w);
	R[8] = 1 - 2 * (x * x + y * y);
}

double mvod_rot_angle(const double R[9])
{
	/* acos is ill-conditioned near 0; atan2 of |axis| and cos keeps small angles exact. */
	double c = 0.5 * (R[0] + R[4] + R[8] - 1.0);
	double ax = R[7] - R[5], ay = R[2] - R[6], az = R[3] - R[1];
	double s = 0.5 * sqrt(ax * ax + ay * ay + az * az);
	return atan2(s, c);
}

void mvod_rot_exp(const double w[3], double R[9])
{
	double th = mvod_vec3_norm(w);
	if (th < 1e-15) {
		struct mvod_pose p;
		mvod_pose_identity(&p);
		memcpy(R, p.R, sizeof(p.R));
		return;
	}
	double k[3] = {w[0] / th, w[1] / th, w[2] / th};
	double c = cos(th), s = sin(th), v = 1.0 - c;
	R[0] = c + k[0] * k[0] * v;
	R[1] = k[0] * k[1] * v - k[2] * s;
	R[2] = k[0] * k[2] * v + k[1] * s;
	R[3] = k[1] * k[0] * v + k[2] * s;
	R[4] = c + k[1] * k[1] * v;
	R[5] = k[1] * k[2] * v - k[0] * s;
	R[6] = k[2] * k[0] * v - k[1] * s;
	R[7] = k[2] * k[1] * v + k[0] * s;
	R[8] = c + k[2] * k[2] * v;
}

void mvod_rot_log(const double R[9], double w[3])
{
	/* Through the quaternion (w >= 0): atan2 stays exact near 0 and near pi. */
	double q[4];
	mvod_rot_to_quat(R, q);
	double n = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
	double f = n < 1e-15 ? 2.0 : 2.0 * atan2(n, q[0]) / n;
	for (int k = 0; k < 3; k++)
		w[k] = f * q[k + 1];
}

bool mvod_rot_reorthonormalise(double R[9], double tol)
{
	double e = 0;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) {
			double d = R[r] * R[c] + R[3 + r] * R[3 + c] + R[6 + r] * R[6 + c] - (r == c);
			e += d * d;
		}
	if (!(sqrt(e) > tol))
		return false;
	double q[4];
	mvod_rot_to_quat(R, q);
	mvod_quat_to_rot(q, R);
	return true;
}

void mvod_vec3_cross(const double a[3], const double b[3], double out[3])
{
	out[0] = a[1] * b[2] - a[2] * b[1];
	out[1] = a[2] * b[0] - a[0] * b[2];
	out[2] = a[0] * b[1] - a[1] * b[0];
}

double mvod_vec3_angle(const double a[3], const double b[3])
{
	double na = mvod_vec3_norm(a), nb = mvod_vec3_norm(b);
	if (na == 0.0 || nb == 0.0)
		return 0.0;
	double c[3];
	mvod_vec3_cross(a, b, c);
	return atan2(mvod_vec3_norm(c), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
}

bool mvod_linsolve(double *A, double *b, int n)
{
	for (int c = 0; c < n; c++) {
		int piv = c;
		for (int r = c + 1; r < n; r++)
			if (fabs(A[n * r + c]) > fabs(A[n * piv + c]))
				piv = r;
		if (!(fabs(A[n * piv + c]) > 1e-300))
			return false;
		for (int q = 0; q < n; q++) {
			double s = A[n * c + q];
			A[n * c + q] = A[n * piv + q];
			A[n * piv + q] = s;
		}
		double s = b[c];
		b[c] = b[piv];
		b[piv] = s;
		for (int r = c + 1; r < n; r++) {
			double f = A[n * r + c] / A[n * c + c];
			for (int q = c; q < n; q++)
				A[n * r + q] -= f * A[n * c + q];
			b[r] -= f * b[c];
		}
	}
	for (int c = n - 1; c >= 0; c--) {
		for (int q = c + 1; q < n; q++)
			b[c] -= A[n * c + q] * b[q];
		b[c] /= A[n * c + c];
	}
	return true;
}
