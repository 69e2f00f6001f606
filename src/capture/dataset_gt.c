/*
 * A dataset's ground truth as mvod compares against it: poses of the camera (the body pose
 * times T_BS), at the frames' own times (interpolated between the two poses around each),
 * relative to the first of them, so in mvod's world (the first camera frame, OpenCV axes).
 */
#include "capture/dataset.h"
#include "util/lines.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/*
 * A frame between two ground-truth poses at most this far apart gets their interpolation:
 * 20 ms, the largest time difference the TUM benchmark's associate.py accepts by default.
 * EuRoC's poses are 5 ms apart, TUM's 10 ms; a wider gap is the motion capture losing track.
 */
#define GT_MAX_GAP_NS 20000000

/* The camera poses of the ground-truth file, in its own world and time order. */
struct samples {
	const struct mvod_dataset *ds;
	int64_t *ns;
	struct mvod_pose *pose;
	size_t n, cap;
	size_t first_line, last_line;
};

static int grow(struct samples *g)
{
	size_t cap = g->cap ? 2 * g->cap : 4096;
	int64_t *ns = realloc(g->ns, cap * sizeof(*ns));
	if (!ns)
		return -ENOMEM;
	g->ns = ns;
	struct mvod_pose *pose = realloc(g->pose, cap * sizeof(*pose));
	if (!pose)
		return -ENOMEM;
	g->pose = pose;
	g->cap = cap;
	return 0;
}

static int add_line(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct samples *g = ctx;
	const struct mvod_dataset *ds = g->ds;
	int64_t ns;
	struct mvod_pose body;
	char why[256] = "";
	if (ds->gt_line(line, &ns, &body, why, sizeof(why)) < 0)
		return why[0] ? mvod_errf(err, errlen, -EINVAL, "%s line %zu: %s", ds->gt_path,
					  lineno, why)
			      : mvod_errf(err, errlen, -EINVAL, "%s line %zu: \"%.40s\" is not "
					  "\"%s\"", ds->gt_path, lineno, line, ds->gt_layout);
	if (g->n > 0 && ns <= g->ns[g->n - 1])
		return mvod_ds_out_of_order(ds->gt_path, lineno, ns, g->ns[g->n - 1], g->last_line,
					    "poses", err, errlen);
	if (g->n == g->cap && grow(g) < 0)
		return mvod_errf(err, errlen, -ENOMEM, "out of memory reading %s", ds->gt_path);
	/* T_WC = T_WB T_BS: the camera's pose from the body's. */
	mvod_pose_compose(&body, &ds->body_cam, &g->pose[g->n]);
	g->ns[g->n++] = ns;
	if (g->n == 1)
		g->first_line = lineno;
	g->last_line = lineno;
	return 0;
}

/* Position linear, rotation along the great arc (slerp), s in [0, 1] from a to b. */
static void interpolate(const struct mvod_pose *a, const struct mvod_pose *b, double s,
			struct mvod_pose *out)
{
	double qa[4], qb[4], q[4], dot = 0;
	mvod_rot_to_quat(a->R, qa);
	mvod_rot_to_quat(b->R, qb);
	for (int k = 0; k < 4; k++)
		dot += qa[k] * qb[k];
	double sign = dot < 0 ? -1 : 1; /* q and -q are one rotation: take the short way */
	double th = acos(fmin(fabs(dot), 1.0)), wa = 1 - s, wb = s;
	if (th > 1e-12) {
		wa = sin((1 - s) * th) / sin(th);
		wb = sin(s * th) / sin(th);
	}
	for (int k = 0; k < 4; k++)
		q[k] = wa * qa[k] + sign * wb * qb[k];
	mvod_quat_to_rot(q, out->R);
	for (int k = 0; k < 3; k++)
		out->t[k] = a->t[k] + s * (b->t[k] - a->t[k]);
}

/* The pose at time t, moving *j (the sample at or before t) forward; false when none. */
static bool pose_at(const struct samples *g, size_t *j, int64_t t, struct mvod_pose *out)
{
	while (*j + 1 < g->n && g->ns[*j + 1] <= t)
		(*j)++;
	if (g->ns[*j] == t) {
		*out = g->pose[*j];
		return true;
	}
	if (g->ns[*j] > t || *j + 1 >= g->n || g->ns[*j + 1] - g->ns[*j] > GT_MAX_GAP_NS)
		return false;
	/* Differences in int64 first: a double holds 1.4e18 ns only to 256 ns. */
	double s = (double)(t - g->ns[*j]) / (double)(g->ns[*j + 1] - g->ns[*j]);
	interpolate(&g->pose[*j], &g->pose[*j + 1], s, out);
	return true;
}

/* One pose per frame that has one, relative to the first; t = the frame's utime in s. */
static int resample(const struct samples *g, const struct mvod_dataset *ds, struct mvod_traj *out)
{
	size_t n = ds->images.n, j = 0;
	out->t = malloc(n * sizeof(*out->t));
	out->pose = malloc(n * sizeof(*out->pose));
	if (!out->t || !out->pose)
		return -ENOMEM;
	struct mvod_pose first_inv, p;
	for (size_t i = 0; i < n; i++) {
		if (!pose_at(g, &j, ds->frame_ns[i], &p))
			continue;
		if (out->n == 0)
			mvod_pose_inverse(&p, &first_inv);
		mvod_pose_compose(&first_inv, &p, &out->pose[out->n]);
		if (out->n == 0)
			mvod_pose_identity(&out->pose[0]); /* exactly, not to rounding */
		out->t[out->n++] = ds->images.times_us[i] / 1e6;
	}
	return 0;
}

static int no_overlap(const struct samples *g, const struct mvod_dataset *ds, char *err,
		      size_t errlen)
{
	char g0[24], g1[24], f0[24], f1[24];
	return mvod_errf(err, errlen, -ENODATA, "%s (lines %zu..%zu, t = %s .. %s s) has no pose "
			 "for any frame of %s (lines %zu..%zu, t = %s .. %s s): the times do not "
			 "overlap (a pose counts when one lies within 20 ms on each side); is it "
			 "this sequence's ground truth?", ds->gt_path, g->first_line, g->last_line,
			 mvod_ds_seconds(g->ns[0], g0), mvod_ds_seconds(g->ns[g->n - 1], g1),
			 ds->index, ds->index_first, ds->index_last,
			 mvod_ds_seconds(ds->frame_ns[0], f0),
			 mvod_ds_seconds(ds->frame_ns[ds->images.n - 1], f1));
}

int mvod_ds_ground_truth(void *priv, struct mvod_traj *gt, char *from, size_t fromlen,
			 char *err, size_t errlen)
{
	const struct mvod_dataset *ds = priv;
	if (!ds->gt_path[0])
		return -ENOENT;
	snprintf(from, fromlen, "%s", ds->gt_path);
	*gt = (struct mvod_traj){.format = MVOD_TRAJ_TUM};
	struct samples g = {.ds = ds};
	int ret = mvod_lines_each(ds->gt_path, "ground truth", add_line, &g, err, errlen);
	if (ret == 0 && g.n == 0)
		ret = mvod_errf(err, errlen, -ENODATA, "%s holds no poses", ds->gt_path);
	if (ret == 0 && resample(&g, ds, gt) < 0)
		ret = mvod_errf(err, errlen, -ENOMEM, "out of memory resampling %s", ds->gt_path);
	if (ret == 0 && gt->n == 0)
		ret = no_overlap(&g, ds, err, errlen);
	if (ret < 0)
		mvod_traj_free(gt);
	free(g.ns);
	free(g.pose);
	return ret;
}
