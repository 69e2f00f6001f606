#include "mvod/eval.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "util/linalg.h"

#define RAD2DEG (180.0 / M_PI)

static void centroid(const double *p, int n, double c[3])
{
	c[0] = c[1] = c[2] = 0;
	for (int i = 0; i < n; i++)
		for (int k = 0; k < 3; k++)
			c[k] += p[3 * i + k] / n;
}

int mvod_umeyama(const double *src, const double *dst, int n, bool with_scale, double R[9],
		 double t[3], double *s)
{
	if (n < 3)
		return -EINVAL;
	double ms[3], md[3], C[9] = {0}, var = 0;
	centroid(src, n, ms);
	centroid(dst, n, md);
	for (int i = 0; i < n; i++) {
		double a[3], b[3];
		for (int k = 0; k < 3; k++) {
			a[k] = src[3 * i + k] - ms[k];
			b[k] = dst[3 * i + k] - md[k];
		}
		var += (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) / n;
		for (int r = 0; r < 3; r++)
			for (int c = 0; c < 3; c++)
				C[3 * r + c] += b[r] * a[c] / n;
	}
	if (var < 1e-18)
		return -EINVAL;
	double trace;
	int ret = mvod_nearest_rotation(C, R, &trace);
	if (ret)
		return ret;
	*s = with_scale ? trace / var : 1.0;
	double Rm[3];
	mvod_mat3_vec(R, ms, Rm);
	for (int k = 0; k < 3; k++)
		t[k] = md[k] - *s * Rm[k];
	return 0;
}

void mvod_sim3_apply(const double R[9], const double t[3], double s, double *xyz, int n)
{
	for (int i = 0; i < n; i++) {
		double *p = xyz + 3 * i;
		mvod_mat3_vec(R, p, p);
		for (int k = 0; k < 3; k++)
			p[k] = s * p[k] + t[k];
	}
}

double mvod_ate_rmse(const double *src, const double *dst, int n, const double R[9],
		     const double t[3], double s)
{
	double sum = 0;
	for (int i = 0; i < n; i++) {
		double p[3];
		mvod_mat3_vec(R, src + 3 * i, p);
		for (int k = 0; k < 3; k++) {
			double d = s * p[k] + t[k] - dst[3 * i + k];
			sum += d * d;
		}
	}
	return n ? sqrt(sum / n) : 0.0;
}

/* Below this a ground-truth step is a held or static frame: there is no step to compare with. */
#define MIN_STEP_M 1e-3

/* Length of steps first .. first + k - 1 of a path, step i going from point i - 1 to point i. */
static double path_len(const double *p, int first, int k)
{
	double len = 0;
	for (int i = first; i < first + k; i++)
		len += mvod_vec3_dist(p + 3 * i, p + 3 * (i - 1));
	return len;
}

void mvod_path_motion(const double *xyz, int n, double *length, double *extent)
{
	*length = n > 1 ? path_len(xyz, 1, n - 1) : 0;
	*extent = 0;
	for (int i = 1; i < n; i++)
		*extent = fmax(*extent, mvod_vec3_dist(xyz + 3 * i, xyz));
}

int mvod_scale_drift(const double *est, const double *gt, int n, double *drift)
{
	double lo = INFINITY, hi = 0;
	int windows = 0;
	/* Steps 1..n-1; window k covers steps 20k+1 .. 20k+20, the whole windows only. */
	for (int first = 1; first + MVOD_DRIFT_WINDOW <= n; first += MVOD_DRIFT_WINDOW) {
		double g = path_len(gt, first, MVOD_DRIFT_WINDOW);
		if (g <= 1e-6) /* eval.py's threshold: a standing window has no scale */
			continue;
		double s = path_len(est, first, MVOD_DRIFT_WINDOW) / g;
		lo = fmin(lo, s);
		hi = fmax(hi, s);
		windows++;
	}
	if (!windows || hi <= 0)
		return -EINVAL;
	*drift = lo > 0 ? hi / lo : INFINITY; /* a window the estimate stood through: collapsed */
	return 0;
}

double mvod_rot_euler_y(const double R[9])
{
	return atan2(-R[6], sqrt(R[0] * R[0] + R[3] * R[3]));
}

/*
 * The world-frame step from a to b: dR = R_b R_a^T, dt = t_b - t_a. It is not the pose b a^-1
 * (whose translation is t_b - dR t_a); the pose struct is only a container.
 */
static void world_step(const struct mvod_pose *a, const struct mvod_pose *b, struct mvod_pose *out)
{
	mvod_mat3_mul_bt(b->R, a->R, out->R);
	for (int k = 0; k < 3; k++)
		out->t[k] = b->t[k] - a->t[k];
}

void mvod_frame_err(const struct mvod_pose *e0, const struct mvod_pose *e1,
		    const struct mvod_pose *g0, const struct mvod_pose *g1,
		    struct mvod_frame_err *out)
{
	struct mvod_pose de, dg;
	world_step(e0, e1, &de);
	world_step(g0, g1, &dg);
	double M[9], Rge[9], te[3];
	mvod_mat3_mul_bt(de.R, dg.R, M);
	out->r_deg = fabs(mvod_rot_euler_y(M)) * RAD2DEG;
	/* The estimated step, carried into the ground truth's world by the current orientation error. */
	mvod_mat3_mul_bt(g1->R, e1->R, Rge);
	mvod_mat3_vec(Rge, de.t, te);
	memcpy(out->gt_step, dg.t, sizeof(out->gt_step));
	memcpy(out->est_step, te, sizeof(out->est_step));
	out->d_m = mvod_vec3_dist(dg.t, te);
	out->e = mvod_frame_err_scaled(out, 1.0);
}

double mvod_frame_err_scaled(const struct mvod_frame_err *fe, double scale)
{
	double est[3];
	for (int k = 0; k < 3; k++)
		est[k] = scale * fe->est_step[k];
	double s = fe->r_deg + mvod_vec3_dist(fe->gt_step, est);
	return s / (0.5 + s);
}

/* Relative motion from pose a to pose b, expressed in a's frame: a^-1 b. */
static void relative(const struct mvod_pose *a, const struct mvod_pose *b, struct mvod_pose *out)
{
	struct mvod_pose ia;
	mvod_pose_inverse(a, &ia);
	mvod_pose_compose(&ia, b, out);
}

/* Mean fields hold sums until mvod_rpe_finish. */
static void tally(double *sum, double *max, double v)
{
	*sum += v;
	if (v > *max)
		*max = v;
}

/*
 * The direction error of an estimate that held still while the ground truth moved: it knows
 * no direction, and a direction drawn at random is off by 90 deg on average. Leaving such
 * steps out would score a motionless estimate as perfect.
 */
#define HELD_STEP_DIR_DEG 90.0

/* The translation terms of relative steps de (estimate) and dg (ground truth). */
static void rpe_add_step(struct mvod_rpe *acc, const double de[3], const double dg[3])
{
	double step = mvod_vec3_norm(dg);
	if (step <= MIN_STEP_M)
		return;
	acc->trans_pct_mean += 100 * mvod_vec3_dist(de, dg) / step;
	acc->n_pct++;
	double dir = mvod_vec3_norm(de) > 1e-9 ? mvod_vec3_angle(de, dg) * RAD2DEG
						: HELD_STEP_DIR_DEG;
	tally(&acc->dir_deg_mean, &acc->dir_deg_max, dir);
	acc->n_dir++;
}

struct mvod_frame_err mvod_rpe_add(struct mvod_rpe *acc, const struct mvod_pose *e0,
				   const struct mvod_pose *e1, const struct mvod_pose *g0,
				   const struct mvod_pose *g1)
{
	struct mvod_pose de, dg;
	relative(e0, e1, &de);
	relative(g0, g1, &dg);
	double dR[9];
	mvod_mat3_mul_bt(de.R, dg.R, dR);
	tally(&acc->rot_deg_mean, &acc->rot_deg_max, mvod_rot_angle(dR) * RAD2DEG);
	acc->n++;
	rpe_add_step(acc, de.t, dg.t);
	struct mvod_frame_err fe;
	mvod_frame_err(e0, e1, g0, g1, &fe);
	tally(&acc->err_avg, &acc->err_max, fe.e);
	return fe;
}

void mvod_rpe_finish(struct mvod_rpe *acc)
{
	if (acc->n)
		acc->rot_deg_mean /= acc->n;
	if (acc->n_dir)
		acc->dir_deg_mean /= acc->n_dir;
	if (acc->n_pct)
		acc->trans_pct_mean /= acc->n_pct;
	acc->err_avg /= acc->n + 1;
}

void mvod_rpe_rescale_err(struct mvod_rpe *acc, const struct mvod_frame_err *fe, int n,
			  double scale)
{
	acc->err_avg = acc->err_max = 0;
	for (int i = 0; i < n; i++)
		tally(&acc->err_avg, &acc->err_max, mvod_frame_err_scaled(&fe[i], scale));
	acc->err_avg /= n + 1; /* as mvod_rpe_finish: the first frame's e is 0 */
}

static const double kitti_len_m[] = {100, 200, 300, 400, 500, 600, 700, 800};
#define KITTI_LENGTHS ((int)(sizeof(kitti_len_m) / sizeof(kitti_len_m[0])))
#define KITTI_STEP 10 /* frames between segment starts: one second of KITTI's 10 Hz */

/* Adds one segment's translation and rotation error per metre of nominal length len. */
static void kitti_add_segment(const struct mvod_pose *est, const struct mvod_pose *gt, int first,
			      int last, double len, double sum[2])
{
	struct mvod_pose dg, de, err;
	relative(&gt[first], &gt[last], &dg);
	relative(&est[first], &est[last], &de);
	relative(&de, &dg, &err);
	sum[0] += mvod_vec3_norm(err.t) / len;
	sum[1] += mvod_rot_angle(err.R) / len;
}

void mvod_kitti_segments(const struct mvod_pose *est, const struct mvod_pose *gt, int n,
			 double *dist, struct mvod_kitti_rel *out)
{
	for (int i = 0; i < n; i++)
		dist[i] = i ? dist[i - 1] + mvod_vec3_dist(gt[i].t, gt[i - 1].t) : 0;
	int last[KITTI_LENGTHS] = {0};
	double sum[2] = {0, 0};
	out->n_segments = 0;
	for (int f = 0; f < n; f += KITTI_STEP)
		for (int k = 0; k < KITTI_LENGTHS; k++) {
			/*
			 * The devkit's lastFrameFromSegmentLength, resumed where the previous start
			 * left it: dist never decreases, so neither does the answer. Once a length
			 * runs off the end, so do the longer ones.
			 */
			while (last[k] < n && !(dist[last[k]] > dist[f] + kitti_len_m[k]))
				last[k]++;
			if (last[k] == n)
				break;
			kitti_add_segment(est, gt, f, last[k], kitti_len_m[k], sum);
			out->n_segments++;
		}
	/* NAN, not 0, when nothing was measured: a report must not show it as a perfect score. */
	int m = out->n_segments;
	out->t_rel_pct = m ? 100 * sum[0] / m : NAN;
	out->r_rel_deg_100m = m ? 100 * RAD2DEG * sum[1] / m : NAN;
}
