#include "mvod/traj.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util/errbuf.h"
#include "util/output.h"
#include "util/lines.h"

const char *const mvod_traj_format_names[] = {"tum", "kitti", NULL};

const char *mvod_traj_format_name(enum mvod_traj_format fmt)
{
	return (unsigned)fmt < 2 ? mvod_traj_format_names[fmt] : "unknown";
}

struct mvod_traj_writer {
	struct mvod_output *out; /* the output policy: locked, truncated at the first line */
	enum mvod_traj_format fmt;
};

int mvod_traj_writer_open(const char *path, enum mvod_traj_format fmt,
			  struct mvod_traj_writer **out, char *err, size_t errlen)
{
	struct mvod_traj_writer *w = calloc(1, sizeof(*w));
	if (!w)
		return mvod_errf(err, errlen, -ENOMEM, "trajectory %s: out of memory", path);
	int ret = mvod_output_open("trajectory", path, &w->out, err, errlen);
	if (ret) {
		free(w);
		return ret;
	}
	w->fmt = fmt;
	*out = w;
	return 0;
}

int mvod_traj_writer_reopen(struct mvod_traj_writer *w, char *err, size_t errlen)
{
	return mvod_output_reopen(w->out, err, errlen);
}

/* -0 + 0 is +0: an identity pose prints as "0", not "-0", which reads like a sign bug. */
static double z(double v)
{
	return v + 0.0;
}

static int format_line(enum mvod_traj_format fmt, double t, const struct mvod_pose *p, char *buf,
		       size_t len)
{
	const double *R = p->R, *T = p->t;
	if (fmt == MVOD_TRAJ_TUM) {
		double q[4];
		mvod_rot_to_quat(R, q);
		return snprintf(buf, len, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", t, z(T[0]),
				z(T[1]), z(T[2]), z(q[1]), z(q[2]), z(q[3]), z(q[0]));
	}
	return snprintf(buf, len, "%.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e\n",
			z(R[0]), z(R[1]), z(R[2]), z(T[0]), z(R[3]), z(R[4]), z(R[5]), z(T[1]),
			z(R[6]), z(R[7]), z(R[8]), z(T[2]));
}

int mvod_traj_writer_add(struct mvod_traj_writer *w, double t, const struct mvod_pose *pose)
{
	char line[512];
	int len = format_line(w->fmt, t, pose, line, sizeof(line));
	if (len < 0 || len >= (int)sizeof(line))
		return -EOVERFLOW;
	/* One write(2) per line: a killed process never leaves a partial line behind. */
	return mvod_output_write(w->out, line, (size_t)len);
}

int mvod_traj_writer_close(struct mvod_traj_writer *w)
{
	if (!w)
		return 0;
	int ret = mvod_output_close(w->out);
	free(w);
	return ret;
}

/*
 * Counts whitespace-separated numbers on a line; 0 for blank and '#' comment lines, -1 when
 * it holds text, -2 for a non-finite number.
 */
static int parse_numbers(const char *line, double *v, int max)
{
	int n = 0;
	const char *s = line;
	while (*s == ' ' || *s == '\t')
		s++;
	if (*s == '#' || *s == '\n' || *s == '\r' || *s == '\0')
		return 0;
	for (;;) {
		char *end;
		double x = strtod(s, &end);
		if (end == s)
			break;
		/* strtod takes "nan" and "inf": a pose with one is no pose. */
		if (!isfinite(x))
			return -2;
		if (n < max)
			v[n] = x;
		n++;
		s = end;
	}
	while (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\n')
		s++;
	return *s ? -1 : n;
}

/* Finite, and on Earth. */
static int check_position(const double t[3], char *why, size_t whylen)
{
	double n = hypot(hypot(t[0], t[1]), t[2]); /* no overflow on the way to 1e308 */
	if (n <= MVOD_POSE_MAX_M)
		return 0;
	return mvod_errf(why, whylen, -EINVAL, "position (%g %g %g) m is %s: no pose on Earth is "
			 "more than %g m from the origin", t[0], t[1], t[2],
			 isfinite(n) ? "that far" : "not finite", MVOD_POSE_MAX_M);
}

int mvod_pose_from_quat(const double t[3], const double q[4], struct mvod_pose *p, char *why,
			size_t whylen)
{
	int ret = check_position(t, why, whylen);
	double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
	if (!ret && !(fabs(len - 1) <= MVOD_POSE_UNIT_TOL))
		ret = mvod_errf(why, whylen, -EINVAL, "quaternion (qx qy qz qw) = (%g %g %g %g) "
				"has length %g, not 1 (within %g): no rotation", q[1], q[2], q[3],
				q[0], len, MVOD_POSE_UNIT_TOL);
	if (ret)
		return ret;
	memcpy(p->t, t, sizeof(p->t));
	mvod_quat_to_rot(q, p->R);
	return 0;
}

int mvod_pose_from_matrix(const double rt[12], struct mvod_pose *p, char *why, size_t whylen)
{
	struct mvod_pose m;
	for (int r = 0; r < 3; r++) {
		memcpy(m.R + 3 * r, rt + 4 * r, 3 * sizeof(double));
		m.t[r] = rt[4 * r + 3];
	}
	int ret = check_position(m.t, why, whylen);
	double RtR[9], off = 0, det = mvod_mat3_det(m.R);
	mvod_mat3_mul_at(m.R, m.R, RtR);
	for (int k = 0; k < 9; k++)
		off = fmax(off, fabs(RtR[k] - (k % 4 == 0)));
	/* A nan anywhere in R makes det nan, which no comparison passes. */
	if (!ret && !(off <= MVOD_POSE_UNIT_TOL && det > 0))
		ret = mvod_errf(why, whylen, -EINVAL, "rotation [%g %g %g; %g %g %g; %g %g %g] is "
				"no rotation: R^T R is %g off the identity (within %g), det R = %g",
				m.R[0], m.R[1], m.R[2], m.R[3], m.R[4], m.R[5], m.R[6], m.R[7],
				m.R[8], off, MVOD_POSE_UNIT_TOL, det);
	if (!ret)
		*p = m;
	return ret;
}

/* A line's numbers (v: 8 of TUM or 12 of KITTI) into t and p; -EINVAL with why. */
static int pose_from_numbers(enum mvod_traj_format fmt, const double *v, double *t,
			     struct mvod_pose *p, char *why, size_t whylen)
{
	*t = fmt == MVOD_TRAJ_KITTI ? 0 : v[0];
	if (fmt == MVOD_TRAJ_KITTI)
		return mvod_pose_from_matrix(v, p, why, whylen);
	const double q[4] = {v[7], v[4], v[5], v[6]};
	return mvod_pose_from_quat(v + 1, q, p, why, whylen);
}

static int traj_push(struct mvod_traj *tr, int *cap, double t, const struct mvod_pose *p)
{
	if (tr->n == *cap) {
		int ncap = *cap ? 2 * *cap : 1024;
		double *nt = realloc(tr->t, (size_t)ncap * sizeof(*nt));
		if (!nt)
			return -ENOMEM;
		tr->t = nt;
		struct mvod_pose *np = realloc(tr->pose, (size_t)ncap * sizeof(*np));
		if (!np)
			return -ENOMEM;
		tr->pose = np;
		*cap = ncap;
	}
	tr->t[tr->n] = t;
	tr->pose[tr->n] = *p;
	tr->n++;
	return 0;
}

/* Line lineno held n numbers (parse_numbers' count or code) where cols were expected. */
static int bad_line(const char *path, int lineno, int cols, int n, char *err, size_t errlen)
{
	char found[32] = "text";
	if (n == -2)
		snprintf(found, sizeof(found), "nan or inf");
	else if (n >= 0)
		snprintf(found, sizeof(found), "%d", n);
	const char *want = cols == 8 ? "8" : cols ? "12" : "8 or 12";
	const char *layout = cols == 8 ? "TUM: t tx ty tz qx qy qz qw"
			     : cols    ? "KITTI: a row-major 3x4 pose"
				       : "TUM or KITTI";
	return mvod_errf(err, errlen, -EINVAL, "%s:%d: expected %s numbers (%s), found %s", path,
			 lineno, want, layout, found);
}

/* What mvod_traj_load gathers, line by line. */
struct loader {
	const char *path;
	struct mvod_traj tr;
	int cap, cols;
};

static int load_line(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct loader *l = ctx;
	double v[12];
	int n = parse_numbers(line, v, 12);
	if (n == 0)
		return 0;
	if (l->cols == 0 && (n == 8 || n == 12)) {
		l->cols = n;
		l->tr.format = n == 8 ? MVOD_TRAJ_TUM : MVOD_TRAJ_KITTI;
	}
	if (n != l->cols)
		return bad_line(l->path, (int)lineno, l->cols, n, err, errlen);
	double t;
	struct mvod_pose p;
	char why[256];
	if (pose_from_numbers(l->tr.format, v, &t, &p, why, sizeof(why)))
		return mvod_errf(err, errlen, -EINVAL, "%s:%zu: %s (%s)", l->path, lineno, why,
				 l->cols == 8 ? "TUM: t tx ty tz qx qy qz qw"
					      : "KITTI: a row-major 3x4 pose");
	return traj_push(&l->tr, &l->cap, t, &p);
}

int mvod_traj_load(const char *path, struct mvod_traj *out, char *err, size_t errlen)
{
	/* Ground truth is an input: the line reader notes it, so no output of the run may be it. */
	struct loader l = {.path = path};
	int ret = mvod_lines_each(path, "trajectory", load_line, &l, err, errlen);
	if (!ret && l.tr.n == 0)
		ret = mvod_errf(err, errlen, -EINVAL, "%s: no poses (an empty file, or only comments)",
				path);
	if (ret)
		mvod_traj_free(&l.tr);
	else
		*out = l.tr;
	return ret;
}

void mvod_traj_free(struct mvod_traj *traj)
{
	free(traj->t);
	free(traj->pose);
	traj->t = NULL;
	traj->pose = NULL;
	traj->n = 0;
}

int mvod_path_init(struct mvod_path *p, int cap)
{
	*p = (struct mvod_path){.cap = cap < 2 ? 2 : cap, .stride = 1};
	size_t size = (size_t)p->cap * 3 * sizeof(double);
	p->xyz = malloc(size);
	if (!p->xyz)
		return -ENOMEM;
	/* Touched now, so that resident memory holds still while the path fills up. */
	memset(p->xyz, 0, size);
	return 0;
}

void mvod_path_add(struct mvod_path *p, const double xyz[3])
{
	if (p->seen++ % p->stride != 0)
		return;
	if (p->n == p->cap) {
		/* Keep every second point: the path keeps its shape and its memory. */
		for (int i = 0; i < p->n / 2; i++)
			memcpy(p->xyz + 3 * i, p->xyz + 6 * i, 3 * sizeof(double));
		p->n /= 2;
		p->stride *= 2;
		if ((p->seen - 1) % p->stride != 0)
			return;
	}
	memcpy(p->xyz + 3 * p->n, xyz, 3 * sizeof(double));
	p->n++;
}

void mvod_path_fini(struct mvod_path *p)
{
	free(p->xyz);
	p->xyz = NULL;
	p->n = 0;
}
