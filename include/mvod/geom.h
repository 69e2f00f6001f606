/* Rigid-body helpers. Matrices are 3x3 row-major double[9]. */
#ifndef MVOD_GEOM_H
#define MVOD_GEOM_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * A camera-to-world pose: X_world = R * X_cam + t. The world frame is the first camera's
 * frame, OpenCV convention (x right, y down, z forward).
 */
struct mvod_pose {
	double R[9];
	double t[3];
};

void mvod_pose_identity(struct mvod_pose *p);
/* out = a * b (apply b first); out may alias a or b. */
void mvod_pose_compose(const struct mvod_pose *a, const struct mvod_pose *b, struct mvod_pose *out);
/* out = a^-1; out may alias a. */
void mvod_pose_inverse(const struct mvod_pose *a, struct mvod_pose *out);

void mvod_mat3_mul(const double A[9], const double B[9], double C[9]);    /* C = A B   */
void mvod_mat3_mul_bt(const double A[9], const double B[9], double C[9]); /* C = A B^T */
void mvod_mat3_mul_at(const double A[9], const double B[9], double C[9]); /* C = A^T B */
void mvod_mat3_vec(const double A[9], const double v[3], double out[3]);
void mvod_mat3_tvec(const double A[9], const double v[3], double out[3]); /* A^T v */
/* out = R X + t: a point moved by a rigid motion (out may be X) */
void mvod_rigid_apply(const double R[9], const double t[3], const double X[3], double out[3]);
/*
 * A camera-from-world pose R, t whose world is scaled by s about centre (world frame): the
 * camera's centre c goes to centre + s (c - centre), its rotation stays; t becomes
 * s t + (s - 1) R centre.
 */
void mvod_rigid_scale(const double R[9], double t[3], const double centre[3], double s);
/*
 * Pixel uv of point c in a pinhole camera's frame, K = fx, fy, cx, cy (no distortion: mvod's
 * frames are undistorted); false when c is not in front of the camera (z <= 0 or NaN).
 */
bool mvod_pinhole_pixel(const double K[4], const double c[3], double uv[2]);
/*
 * The motion from camera-from-world pose a (Ra, ta) to b (Rb, tb): X_b = R X_a + t, so
 * R = Rb Ra^T and t = tb - R ta. R and t must not alias the inputs.
 */
void mvod_motion_between(const double Ra[9], const double ta[3], const double Rb[9],
			 const double tb[3], double R[9], double t[3]);
double mvod_vec3_norm(const double v[3]);
/* a . b, summed in the order x, y, z. */
static inline double mvod_vec3_dot(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
/* out = a x b (out must not alias a or b) */
void mvod_vec3_cross(const double a[3], const double b[3], double out[3]);
/*
 * Solves the n x n system A x = b in place (row-major A, Gaussian elimination with partial
 * pivoting): x in b, A destroyed. false when A is singular (a pivot of magnitude <= 1e-300).
 */
bool mvod_linsolve(double *A, double *b, int n);
double mvod_vec3_dist(const double a[3], const double b[3]);
double mvod_mat3_det(const double A[9]);

/* Unit quaternion q = (w, x, y, z) with w >= 0, from a rotation matrix (Shepperd's method). */
void mvod_rot_to_quat(const double R[9], double q[4]);
/* Rotation matrix from a quaternion (w, x, y, z); q need not be normalised. */
void mvod_quat_to_rot(const double q[4], double R[9]);
/* Rotation angle of R in radians, in [0, pi]. */
double mvod_rot_angle(const double R[9]);
/* R = exp([w]x), axis-angle vector w in radians (Rodrigues). */
void mvod_rot_exp(const double w[3], double R[9]);
/* Its inverse: the axis-angle vector (radians, |w| <= pi) of a rotation matrix. */
void mvod_rot_log(const double R[9], double w[3]);
/*
 * R (in and out) brought back onto the rotations when it has left them by more than tol: the
 * Frobenius norm of R^T R - I. Then R becomes the rotation of its quaternion (Shepperd's
 * method reads it from R's largest diagonal combination, normalised). Returns whether R moved;
 * within tol R is left bit for bit.
 */
bool mvod_rot_reorthonormalise(double R[9], double tol);
/* Angle between two vectors in radians; 0 when either is zero. */
double mvod_vec3_angle(const double a[3], const double b[3]);

#ifdef __cplusplus
}
#endif

#endif
